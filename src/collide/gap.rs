//! The smallest distance between layers: sLayer's promise is not only that layers never cross
//! but that every vertex stays the collision distance `d` from every other layer's faces, so
//! tests check the gap as well as the crossings, and `slayer check` reports it.

use rayon::prelude::*;

use crate::geom::point_triangle_distance_squared;
use crate::grid::{GridError, SpatialHash};
use crate::mesh::Mesh;

/// The smallest distance from a live vertex to a live face of another layer, among those
/// within `reach` of each other; `None` when no such pair is that close (or the mesh has one
/// layer). Through a vertex grid of cell `reach`, in parallel.
pub fn smallest_layer_gap(mesh: &Mesh, reach: f32) -> Result<Option<f32>, GridError> {
    if mesh.layer_count() < 2 {
        return Ok(None);
    }
    let max_edge = mesh.edge_length_stats().max as f32;
    let grid = SpatialHash::build(mesh, reach)?;
    let vertex_faces = mesh.vertex_faces();
    let (positions, layers) = (mesh.positions(), mesh.vertex_layers());
    let gap = (0..mesh.vertex_count())
        .into_par_iter()
        .filter(|&v| mesh.is_vertex_live(v as u32))
        .flat_map_iter(|v| {
            let p = positions[v];
            grid.faces_within(positions, mesh.faces(), &vertex_faces, p, reach, max_edge)
                .into_iter()
                .filter(move |&f| mesh.face_layers()[f as usize] != layers[v])
                .map(move |f| {
                    let [a, b, c] = mesh.face_positions(f as usize);
                    point_triangle_distance_squared(p, a, b, c)
                })
        })
        .min_by(f32::total_cmp);
    Ok(gap.map(f32::sqrt).filter(|&g| g <= reach))
}
