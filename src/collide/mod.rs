//! Collision queries between layers and within a layer, and the response to them: the per-step
//! broad phase (a dense face grid over the brush's region), the neighbourhood a vertex skips,
//! sLayer's collision response (the proximity clamp, then the exact backstop), and the exact
//! whole-mesh intersection count that `slayer check`, the bench and the tests use to prove that
//! nothing passed through anything.
//!
//! Floors: `state` ← `region` ← `gap_guard`, `backstop` ← `response`; nothing here imports the pipeline or
//! the GPU, which both build on it.

mod backstop;
mod gap;
mod gap_guard;
mod intersections;
mod local_grid;
pub mod neighbourhood;
mod region;
mod response;
mod rings;
mod sheet;
mod stamps;
mod state;

pub use backstop::Backstop;
pub use gap::smallest_layer_gap;
pub use intersections::{
    IntersectingPair, IntersectionReport, find_intersections, find_intersections_in,
};
pub use local_grid::{LocalFaceGrid, SweptTriangle};
pub use region::{Region, Scratch, StepMoves};
pub use response::{
    CollisionOutcome, MAX_PASSES, clamp_in_region, clamp_moves, clamp_on_a_clear_sheet, collide,
    collide_with, lies_on_a_clear_sheet, pull_back,
};
pub use rings::RingCache;
pub(crate) use sheet::{boundary_loop, normal_cone, projected_loop_is_simple, rim_loop};
pub use stamps::Stamps;
pub use state::StrokeState;
