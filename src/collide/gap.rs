//! The smallest distance between layers: sLayer's promise is not only that layers never cross
//! but that every vertex stays the collision distance `d` from every other layer's faces, so
//! tests check the gap as well as the crossings, and `slayer check` reports it.

use rayon::prelude::*;

use crate::geom::{Aabb, point_triangle_distance_squared};
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
    let box_reach = reach + max_edge;
    let r2 = reach * reach;
    // A face within `reach` of `p` has a vertex within `reach + max_edge`: the faces of the
    // other layers' vertices in that box, each perhaps more than once (a minimum does not
    // mind), and no face of the vertex's own layer, which is most of what is near. A face
    // whose box is farther than the nearest found so far cannot be nearer.
    let gap = (0..mesh.vertex_count())
        .into_par_iter()
        .filter(|&v| mesh.is_vertex_live(v as u32))
        .map(|v| {
            let p = positions[v];
            let mut nearest = f32::INFINITY;
            grid.for_each_in_box(p - box_reach, p + box_reach, |u| {
                if layers[u as usize] == layers[v] {
                    return;
                }
                for &f in vertex_faces.of(u) {
                    let [a, b, c] = mesh.face_positions(f as usize);
                    if Aabb::of_points(&[a, b, c]).distance_squared_to(p) > nearest.min(r2) {
                        continue;
                    }
                    let d2 = point_triangle_distance_squared(p, a, b, c);
                    if d2 <= r2 {
                        nearest = nearest.min(d2);
                    }
                }
            });
            nearest
        })
        .min_by(f32::total_cmp)
        .filter(|d| d.is_finite());
    Ok(gap.map(f32::sqrt).filter(|&g| g <= reach))
}
