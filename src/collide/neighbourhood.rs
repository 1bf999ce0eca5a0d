//! A vertex's own neighbourhood in its layer, which collision tests must skip: a vertex is always
//! close to its incident faces and to the faces just around them.
//!
//! Which ring is enough. Let `ρ` be a lower bound on the altitudes of the faces around a vertex
//! (altitude = twice the area over the longest edge). The faces incident to `v` cover a disk of
//! radius `ρ` around it, and each further ring of faces widens the covered disk by at least `ρ`.
//! So on a surface that is locally a sheet, a face with no vertex within graph distance `r` of
//! `v` is at least `(r + 1)·ρ` away (near an open boundary the covered region is cut, and the
//! far side of a narrow notch can be nearer: it is a different part of the sheet and collides). Skipping the faces that touch the `r`-ring with
//! `(r + 1)·ρ ≥ d` therefore skips exactly the faces that are near only because they are
//! neighbours, and nothing farther: a face of the same layer that comes within `d` from outside
//! the ring is a genuine fold, and collides. `tests/collision.rs` checks both directions on
//! generated and jittered meshes.

use rayon::prelude::*;

use crate::mesh::{Mesh, next, prev};

/// Share of faces allowed to be thinner than the `ρ` used (slivers are few and local; letting one
/// sliver set the ring for the whole mesh would blind collision everywhere).
const ALTITUDE_QUANTILE: f64 = 0.001;
/// Rings are capped: past this the exclusion would hide real folds.
pub const MAX_RING: u32 = 4;

/// The graph distance `r` whose faces a vertex skips, for collision distance `distance`.
pub fn exclusion_ring(mesh: &Mesh, distance: f32) -> u32 {
    let rho = altitude_bound(mesh);
    if rho.is_nan() || rho <= 0.0 {
        return MAX_RING;
    }
    let r = (distance as f64 / rho).ceil() - 1.0;
    (r.max(1.0) as u32).min(MAX_RING)
}

/// Low quantile of face altitudes (twice the area over the longest edge).
pub fn altitude_bound(mesh: &Mesh) -> f64 {
    let mut altitudes: Vec<f64> = (0..mesh.face_count())
        .into_par_iter()
        .filter(|&f| !mesh.is_face_dead(f))
        .map(|f| {
            let [a, b, c] = mesh.face_positions(f).map(|p| p.as_dvec3());
            let twice_area = (b - a).cross(c - a).length();
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            if longest > 0.0 {
                twice_area / longest
            } else {
                0.0
            }
        })
        .collect();
    if altitudes.is_empty() {
        return 0.0;
    }
    let k = ((altitudes.len() as f64 * ALTITUDE_QUANTILE) as usize).min(altitudes.len() - 1);
    let (_, kth, _) = altitudes.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
    *kth
}

/// The vertices within graph distance `ring` of `vertex` (itself included), in `out`, sorted
/// (test membership with [`in_ring`]). `out` is reused between calls.
pub fn ring_vertices(mesh: &Mesh, vertex: u32, ring: u32, out: &mut Vec<u32>) {
    out.clear();
    out.push(vertex);
    let mut frontier_start = 0;
    for _ in 0..ring {
        let frontier_end = out.len();
        for i in frontier_start..frontier_end {
            let u = out[i];
            if mesh.is_boundary_vertex(u) {
                let first = mesh.adjacency().vertex_corner[u as usize];
                let w = mesh.corner_vertex(prev(first));
                if !out.contains(&w) {
                    out.push(w);
                }
            }
            for c in mesh.adjacency().corners_around(u) {
                let w = mesh.corner_vertex(next(c));
                if !out.contains(&w) {
                    out.push(w);
                }
            }
        }
        frontier_start = frontier_end;
    }
    out.sort_unstable();
}

/// Whether `w` is in a ring [`ring_vertices`] found. A one-ring (about 7 vertices) is
/// scanned: faster than bisecting it, and the clamp and the sheet bound ask per face.
pub fn in_ring(ring: &[u32], w: u32) -> bool {
    match ring.len() {
        0..=16 => ring.contains(&w),
        _ => ring.binary_search(&w).is_ok(),
    }
}
