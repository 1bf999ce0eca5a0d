//! The GPU path: adapter choice, shader loading and the compute kernels' host side (docs/gpu.md).
//! Each kernel in `wgsl/` has a CPU mirror of the same name in [`crate::cpu`].

mod apply_moves;
mod backend;
mod backstop_filter;
mod brush_frame;
mod cell_keys;
mod context;
mod deform;
mod dispatch_args;
mod gate;
mod hash_table;
mod limits;
mod moving_entries;
mod options;
mod overlay;
mod pages;
mod proximity;
mod reusable;
mod rows;
mod scan;
mod select;
pub mod shaders;
mod topology;
mod vertex_normals;
mod vertices;

// The kernels' structs and constants live in `crate::abi`, shared with the CPU mirrors; they
// stay reachable here under the names the host code has always used.
pub use crate::abi::{
    APPLY_WORKGROUP_SIZE, ApplyMode, ApplyParams, BACKSTOP_WORKGROUP_SIZE, BackstopParams,
    BrushSphere, CellKeyParams, CountParams, CsrTable, DeformParams, DispatchParams,
    ENTRIES_WORKGROUP_SIZE, EntryParams, FACE_WORDS, FRAME_WORKGROUP_SIZE, FrameParams,
    GATE_WORKGROUP_SIZE, GateParams, GateSplit, GateStage, GateStatus, MovingVertex, NormalParams,
    OverlayParams, PAGE_COUNT, PAGE_SHIFT_CONSTANT, PROXIMITY_WORKGROUP_SIZE, ProximityParams,
    PulledVertex, SCAN_BLOCK, SelectParams, SelectedVertex, brush_code, falloff_code,
};

pub use apply_moves::{AppliedMoves, ApplyMovesBuffers, record_apply_moves, run_apply_moves};
pub use backend::{GpuKernels, face_capacity, resident_bytes, vertex_capacity};
pub use backstop_filter::{
    BackstopBuffers, BackstopQuery, PAIRS_GUESS, UndecidedPairs, backstop_inputs, backstop_params,
    backstop_query_params, check_backstop_invocations, moved_edge_bound, record_backstop_filter,
    run_backstop_filter,
};
pub use brush_frame::{frame_sums_buffer, record_brush_frame, run_brush_frame};
pub use cell_keys::{record_cell_keys, run_cell_keys};
#[cfg(test)]
pub(crate) use context::map_read;
pub use context::{AdapterChoice, AdapterSummary, GpuContext, GpuError, Workgroups, list_adapters};
pub use deform::{
    DeformBuffers, SmoothingNeighbours, deform_params, record_deform, run_deform,
    run_framed_deform, smoothing_neighbours,
};
pub use dispatch_args::{indirect_args_buffer, record_dispatch_args, run_dispatch_args};
pub use gate::{
    GateBuffers, record_gate_check, record_gate_open, record_gate_vacate, record_moved_edges,
    run_longest_move, run_moved_edges, run_sample_gate,
};
pub use hash_table::{
    GpuHashTable, read_table, run_cell_counts, run_hash_table, run_scatter, table_size_for,
};
pub use moving_entries::{
    BuiltEntries, BuiltEntryBuffers, EntryBuffers, RING_STRIDE, entry_params,
    record_moving_entries, ring_bytes, run_moving_entries,
};
pub use options::{DEFAULT_GPU_BUDGET_MIB, GpuOptions};
pub use overlay::{
    Filed, Filing, OverlayBuffers, SlotBuffers, TableBuffers, overlay_limit, overlay_table,
    overlay_table_sized, record_overlay_members, record_overlay_table, run_overlay_members,
    run_overlay_table,
};
pub use proximity::{
    ProximityBuffers, ProximityQuery, cells_per_entry, check_invocations, moving_vertices,
    pass_params, proximity_params, proximity_reaches, record_proximity, run_proximity, verdicts,
};
pub use rows::SlottedRows;
pub use scan::{record_exclusive_scan, run_exclusive_scan};
pub use select::{
    GpuSelection, HashedVertices, SELECTION_GUESS, SelectionBuffers, SelectionRead, record_select,
    run_select, run_select_with_overlay, select_params,
};
pub use topology::{PackedTopology, TopologyLayout};
pub use vertex_normals::{
    record_moved_normals, record_vertex_normals, run_moved_normals, run_vertex_normals,
};
pub use vertices::VertexBuffers;
