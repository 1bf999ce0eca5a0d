//! Host copies of the structs the kernels read. `tests/wgsl.rs` checks each size and field
//! offset against naga's layout of the WGSL declaration, so the two cannot drift apart.

use bytemuck::{Pod, Zeroable};

/// `CellKeyParams` in `wgsl/cell_keys.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct CellKeyParams {
    pub count: u32,
    /// Table size minus one; the table size is a power of two.
    pub table_mask: u32,
    pub inv_cell_size: f32,
    pub _pad: u32,
}
