//! The spatial hash's kernels (`cell_keys`, `cell_counts`, `scan`, `scan_add`, `scatter`) and
//! the overlay table's (`overlay_members`, `overlay_keys`, `overlay_entries`): their parameters
//! and the CSR table they build.

use bytemuck::{Pod, Zeroable};

/// Values per block of the exclusive scan: the workgroup size of `wgsl/scan.wgsl` and
/// `wgsl/scan_add.wgsl`.
pub const SCAN_BLOCK: u32 = 256;

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

/// `CountParams` in `wgsl/shared/mesh.wgsl`: the element count of a one-dimensional pass.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct CountParams {
    pub count: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

impl CountParams {
    pub fn new(count: usize) -> Self {
        CountParams {
            count: count as u32,
            _pad0: 0,
            _pad1: 0,
            _pad2: 0,
        }
    }
}

/// `OverlayParams` in `wgsl/shared/overlay.wgsl` (`overlay_members`, `overlay_keys`,
/// `overlay_entries`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct OverlayParams {
    /// Invocations: slots of the moving list (`overlay_members`), of the member list (the
    /// others).
    pub count: u32,
    /// Slots the member list has room for.
    pub room: u32,
    /// Overlay table size minus one.
    pub table_mask: u32,
    pub inv_cell_size: f32,
}

/// A CSR hash table read back to the CPU (or built by the CPU mirrors).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CsrTable {
    /// `table_size + 1` bucket starts; the last is the number of filed vertices.
    pub offsets: Vec<u32>,
    /// Vertex ids, bucket by bucket.
    pub entries: Vec<u32>,
}

impl CsrTable {
    pub fn table_size(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The vertices filed in bucket `bucket`, in table order.
    pub fn bucket(&self, bucket: u32) -> &[u32] {
        let b = bucket as usize;
        &self.entries[self.offsets[b] as usize..self.offsets[b + 1] as usize]
    }

    /// The same table with each bucket sorted by vertex id, so that tables built in different
    /// atomic orders compare equal.
    pub fn canonical(mut self) -> Self {
        for b in 0..self.table_size() {
            let (start, end) = (self.offsets[b] as usize, self.offsets[b + 1] as usize);
            self.entries[start..end].sort_unstable();
        }
        self
    }
}
