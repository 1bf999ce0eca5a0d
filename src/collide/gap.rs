//! The smallest distance between layers: sLayer's promise is not only that layers never cross
//! but that every vertex stays the collision distance `d` from every other layer's faces, so
//! tests check the gap as well as the crossings, and `slayer check` reports it.

use rayon::prelude::*;

use super::LocalFaceGrid;
use crate::geom::{Aabb, point_triangle_distance_squared};
use crate::grid::GridError;
use crate::mesh::Mesh;

/// The smallest distance from a live vertex to a live face of another layer, among those
/// within `reach` of each other; `None` when no such pair is that close (or the mesh has one
/// layer). Through a grid of the faces' boxes of cell `reach`, in parallel; an error for a
/// `reach` that is not a positive length.
pub fn smallest_layer_gap(mesh: &Mesh, reach: f32) -> Result<Option<f32>, GridError> {
    if !(reach.is_finite() && reach > 0.0) {
        return Err(GridError::InvalidCellSize(reach));
    }
    if mesh.layer_count() < 2 {
        return Ok(None);
    }
    let positions = mesh.positions();
    let (vertex_layers, face_layers) = (mesh.vertex_layers(), mesh.face_layers());
    // Every live face with finite corners (`usable`), its box filed in a grid of cell
    // `reach`: a face within `reach` of a point has its box within `reach` of it, so a query
    // of the point's box grown by `reach` meets it, once.
    let (usable, boxes) = super::intersections::face_boxes(mesh);
    let bounds = boxes.iter().fold(Aabb::EMPTY, |b, f| b.including_box(f));
    let mut grid = LocalFaceGrid::default();
    grid.build(&boxes, bounds, reach);
    let r2 = reach * reach;
    // A face whose box is farther than the nearest found so far cannot be nearer.
    let gap = (0..mesh.vertex_count())
        .into_par_iter()
        .filter(|&v| mesh.is_vertex_live(v as u32) && positions[v].is_finite())
        .map(|v| {
            let p = positions[v];
            // Grown past `reach` by more than the box's own rounding.
            let grow = reach * (1.0 + 1e-4) + 4.0 * f32::EPSILON * p.abs().max_element();
            let query = Aabb::of_points(&[p]).expanded(grow);
            let mut nearest = f32::INFINITY;
            grid.for_each_face_once(&query, &boxes, |f| {
                let f = f as usize;
                if !usable[f]
                    || face_layers[f] == vertex_layers[v]
                    || boxes[f].distance_squared_to(p) > nearest.min(r2)
                {
                    return;
                }
                let [a, b, c] = mesh.face_positions(f);
                let d2 = point_triangle_distance_squared(p, a, b, c);
                if d2 <= r2 {
                    nearest = nearest.min(d2);
                }
            });
            nearest
        })
        .min_by(f32::total_cmp)
        .filter(|d| d.is_finite());
    Ok(gap.map(f32::sqrt).filter(|&g| g <= reach))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes;
    use glam::Vec3;
    use rand::{Rng, SeedableRng};

    /// Every live vertex against every face of another layer.
    fn all_pairs(mesh: &Mesh, reach: f32) -> Option<f32> {
        let (positions, layers) = (mesh.positions(), mesh.vertex_layers());
        let mut nearest = f32::INFINITY;
        for v in (0..mesh.vertex_count()).filter(|&v| mesh.is_vertex_live(v as u32)) {
            for (f, ids) in mesh.faces().iter().enumerate() {
                if mesh.face_layers()[f] != layers[v] {
                    let [a, b, c] = ids.map(|w| positions[w as usize]);
                    nearest = nearest.min(point_triangle_distance_squared(positions[v], a, b, c));
                }
            }
        }
        Some(nearest.sqrt()).filter(|&g| g <= reach)
    }

    /// Three sheets squeezed together and jittered: the grid's gap is the all-pairs gap, bit
    /// for bit, and none where no pair is within reach.
    #[test]
    fn the_gap_is_the_smallest_of_all_pairs() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(49);
        let (mut found, mut none) = (0, 0);
        for case in 0..60 {
            let gap = 0.2 + 0.04 * case as f32;
            let mut mesh = shapes::stacked_sheets(3, 6, 6, 1.0, gap);
            for p in mesh.positions_mut() {
                *p += Vec3::from_array([(); 3].map(|_| rng.random_range(-0.3..=0.3)));
            }
            let reach = 0.9;
            let expected = all_pairs(&mesh, reach);
            assert_eq!(
                smallest_layer_gap(&mesh, reach).unwrap(),
                expected,
                "case {case}"
            );
            if expected.is_some() {
                found += 1;
            } else {
                none += 1;
            }
        }
        assert!(
            found > 10 && none > 10,
            "{found} gaps found, {none} beyond reach"
        );
    }
}
