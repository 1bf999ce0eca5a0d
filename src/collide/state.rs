//! What one stroke's steps read and never change: the grid, the active layers, the collision
//! set-up and a bound on the edges. It lives here, in the lowest module that reads all of it,
//! so that the collision response, the brush's selection and deformation (`pipeline::step`)
//! and the GPU kernels share it without `collide` reaching up into the pipeline.

use crate::grid::SpatialHash;

/// Everything a step reads that lasts for the whole stroke.
pub struct StrokeState<'a> {
    pub grid: Option<&'a SpatialHash>,
    pub active: &'a [bool],
    pub parallel: bool,
    /// Collision distance (world units).
    pub collision_distance: f32,
    /// Graph distance of the neighbourhood a vertex skips in its own layer.
    pub ring: u32,
    /// An upper bound on every edge length right now.
    pub max_edge: f32,
    /// Skip the searches that cannot find anything: within a layer where it is a sheet
    /// (`collide::sheet`), against other layers where they have nothing near. Off only to
    /// compare: the results are the same either way.
    pub cull: bool,
}

#[cfg(test)]
impl<'a> StrokeState<'a> {
    /// The unit tests' stroke: on one thread, culling, `d` = 0.5, a ring of 1, every layer of
    /// `active` brushed, `max_edge` as given.
    pub(super) fn for_tests(grid: &'a SpatialHash, active: &'a [bool], max_edge: f32) -> Self {
        StrokeState {
            grid: Some(grid),
            active,
            parallel: false,
            collision_distance: 0.5,
            ring: 1,
            max_edge,
            cull: true,
        }
    }
}
