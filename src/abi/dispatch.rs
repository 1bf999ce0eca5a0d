//! How kernels are dispatched and bound: workgroup sizes, `wgsl/dispatch_args.wgsl`'s
//! parameters, and the paged bindings of `wgsl/shared/pages.wgsl`.

use bytemuck::{Pod, Zeroable};

/// Workgroup size of the one-dimensional kernels; the CPU mirrors walk their invocations in
/// workgroups of this size, as the GPU numbers them.
pub const WORKGROUP_SIZE: u32 = 64;

// Kernels dispatched indirectly, and the gate's, each under its own name: the host sizes their
// dispatches (and `dispatch_args`' parameters) with these, and `tests/wgsl.rs` checks each
// against the shader's `WORKGROUP_SIZE`.
pub const FRAME_WORKGROUP_SIZE: u32 = 64;
pub const APPLY_WORKGROUP_SIZE: u32 = 64;
pub const PROXIMITY_WORKGROUP_SIZE: u32 = 64;
pub const BACKSTOP_WORKGROUP_SIZE: u32 = 64;
pub const ENTRIES_WORKGROUP_SIZE: u32 = 64;
/// Workgroup size of `longest_move` and `sample_gate` (`moved_edges` runs as `moved_normals`).
pub const GATE_WORKGROUP_SIZE: u32 = 64;

/// `DispatchParams` in `wgsl/dispatch_args.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct DispatchParams {
    pub workgroup_size: u32,
    pub max_per_dimension: u32,
    pub capacity: u32,
    pub per_item: u32,
}

/// Bindings a paged array may span (the kernel declares this many in bind group 1).
pub const PAGE_COUNT: u64 = 4;

/// The pipeline-overridable constant in `wgsl/shared/pages.wgsl`.
pub const PAGE_SHIFT_CONSTANT: &str = "PAGE_SHIFT";
