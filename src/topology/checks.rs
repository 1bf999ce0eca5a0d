//! What a topology change must pass before it stays: its holes sewn shut, and its new faces
//! crossing nothing.

use std::collections::HashSet;

use crate::geom::{Aabb, neighbours_overlap, triangles_intersect};
use crate::grid::SpatialHash;
use crate::mesh::{INVALID, Mesh};

/// Every edge of the faces from `first` on has a face on both sides: the holes were closed.
/// (Pinched vertices cannot arise: the holes sewn are simple loops apart from each other,
/// and the remesher keeps the mesh manifold; the tests validate the whole mesh.)
pub fn sewn_shut(mesh: &Mesh, first: usize) -> bool {
    !mesh.adjacency().opposite[3 * first..].contains(&INVALID)
}

/// Whether a face from `first` on meets another face beyond the vertices they share: a quick
/// test of the sewn faces before they are remeshed (the exact count over the whole region
/// comes after). Faces reach the test through `grid`, from their vertices within `reach` of
/// the new face's box; `reach` at least the longest edge near it finds every face it meets.
pub fn new_faces_cross(mesh: &Mesh, grid: &SpatialHash, first: usize, reach: f32) -> bool {
    let corners = |f: usize| mesh.faces()[f];
    let points = |f: usize| mesh.face_positions(f);
    (first..mesh.face_count()).any(|f| {
        let bounds = Aabb::of_points(&points(f)).expanded(reach);
        let mut near = HashSet::new();
        grid.for_each_in_box(bounds.min, bounds.max, |v| {
            near.extend(mesh.faces_around(v));
        });
        near.into_iter().any(|g| {
            let g = g as usize;
            if g == f {
                return false;
            }
            let shared = corners(f).iter().any(|v| corners(g).contains(v));
            match shared {
                true => neighbours_overlap(points(f), corners(f), points(g), corners(g)),
                false => triangles_intersect(points(f), points(g)),
            }
        })
    })
}
