//! CPU mirrors of the WGSL kernels, one file per kernel with the same name. Their loops keep the
//! shader's shape (invocations in the GPU's order through `shared::invocations`, the same
//! guards) so the two read side by side;
//! they are the reference every GPU result is compared with. `hash_table` chains the hash-build
//! mirrors as the GPU host code chains the kernels.
//!
//! The mirrors speak the kernels' language through [`crate::abi`] alone: nothing here reads
//! the GPU path or the pipeline, so either can change without the reference moving.

mod apply_moves;
mod backstop_filter;
mod brush_frame;
mod cell_counts;
mod cell_keys;
mod deform;
mod dispatch_args;
mod hash_table;
mod longest_move;
mod moved_edges;
mod moved_normals;
mod moving_entries;
mod overlay_entries;
mod overlay_keys;
mod overlay_members;
mod proximity;
mod sample_gate;
mod scan;
mod scan_add;
mod scatter;
mod select;
mod shared;
mod vertex_normals;

// The constants the mirrors share with the kernels live in `crate::abi`; they stay reachable
// here under the names the pipeline and the tests have always used.
pub use crate::abi::{
    BACKSTOP_MARGIN, FRAME_NORMAL_FROM_SUMS, FRAME_PLANE_FROM_SUMS, FRAME_SUM_WORDS, FrameSums,
    PULL_SCALE,
};

pub use apply_moves::{ApplyBuffers, apply_moves};
pub use backstop_filter::{BackstopInputs, backstop_filter};
pub use brush_frame::{FrameInputs, brush_frame, frame_from_sums, from_fixed, to_fixed};
pub use cell_counts::cell_counts;
pub use cell_keys::cell_keys;
pub use deform::{DeformInputs, deform};
pub use dispatch_args::dispatch_args;
pub use hash_table::{exclusive_scan, hash_table, overlay_slot_table};
pub use longest_move::longest_move;
pub use moved_edges::moved_edges;
pub use moved_normals::moved_normals;
pub use moving_entries::{EntryInputs, EntryOutputs, moving_entries};
pub use overlay_entries::overlay_entries;
pub use overlay_keys::overlay_keys;
pub use overlay_members::{OverlaySlots, overlay_members};
pub use proximity::{ProximityInputs, proximity};
pub use sample_gate::{GateState, sample_gate};
pub use scan::scan;
pub use scan_add::scan_add;
pub use scatter::scatter;
pub use select::{SelectInputs, select};
pub use shared::{falloff_weight, packed_position};
pub use vertex_normals::{vertex_normal, vertex_normals};
