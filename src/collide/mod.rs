//! Collision queries between layers and within a layer: the per-step broad phase (a dense face
//! grid over the brush's region), the neighbourhood a vertex skips, and the exact whole-mesh
//! intersection count that `slayer check`, the bench and the tests use to prove that nothing
//! passed through anything.

mod intersections;
mod local_grid;
pub mod neighbourhood;
mod stamps;

pub use intersections::{IntersectingPair, IntersectionReport, find_intersections};
pub use local_grid::LocalFaceGrid;
pub use stamps::Stamps;
