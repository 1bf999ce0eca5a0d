//! Collision queries between layers and within a layer. For now: the exact whole-mesh
//! intersection count that `slayer check`, the bench and the tests use to prove that nothing
//! passed through anything.

mod intersections;

pub use intersections::{IntersectingPair, IntersectionReport, find_intersections};
