//! The contract between the kernels in `wgsl/`, their CPU mirrors in [`crate::cpu`] and the GPU
//! host code in [`crate::gpu`]: the `#[repr(C)]` structs the kernels read and write, and the
//! codes and constants all three must agree on. It sits below both sides so that a mirror
//! needs nothing from the GPU path (nor the GPU path from the mirrors) to speak the kernels'
//! language.
//!
//! `tests/wgsl.rs` checks each struct's size and field offsets, and each constant a shader
//! declares, against naga's reading of the WGSL, so the two cannot drift apart.

mod brush;
mod dispatch;
mod gate;
mod hash;
mod moves;

pub use brush::{
    BrushSphere, DeformParams, FRAME_NORMAL_FROM_SUMS, FRAME_PLANE_FROM_SUMS, FRAME_SUM_WORDS,
    FrameParams, FrameSums, SelectParams, SelectedVertex, brush_code, falloff_code, frame_params,
};
pub use dispatch::{
    APPLY_WORKGROUP_SIZE, BACKSTOP_WORKGROUP_SIZE, DispatchParams, ENTRIES_WORKGROUP_SIZE,
    FRAME_WORKGROUP_SIZE, GATE_WORKGROUP_SIZE, PAGE_COUNT, PAGE_SHIFT_CONSTANT,
    PROXIMITY_WORKGROUP_SIZE, WORKGROUP_SIZE,
};
pub use gate::{GateParams, GateSplit, GateStage, GateStatus};
pub use hash::{CellKeyParams, CountParams, CsrTable, OverlayParams, SCAN_BLOCK};
pub use moves::{
    ApplyMode, ApplyParams, BACKSTOP_MARGIN, BackstopParams, CLAMP_SLACK, EntryParams, FACE_WORDS,
    MovingVertex, NormalParams, PULL_SCALE, ProximityParams, PulledVertex,
};
