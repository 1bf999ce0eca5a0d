//! Exact triangle–triangle intersection on closed triangles (touching counts), built only from
//! Shewchuk's adaptive-precision orientation predicates (`robust` crate), so no rounding can hide
//! or invent a crossing.
//!
//! Two non-coplanar triangles meet in a segment of the line where their planes cross; an end of
//! that segment lies on an edge of one triangle and inside the other. So they intersect exactly
//! when one of the six edges meets the other triangle. Coplanar triangles are tested in 2D.

use glam::{DVec3, Vec3};
use robust::{Coord, Coord3D, orient2d, orient3d};

fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

fn orient(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    orient3d(c3(a), c3(b), c3(c), c3(d))
}

fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// True when the closed triangles `a` and `b` share at least one point.
pub fn triangles_intersect(a: [Vec3; 3], b: [Vec3; 3]) -> bool {
    if super::surely_disjoint(a, b) {
        return false;
    }
    let a = a.map(|p| p.as_dvec3());
    let b = b.map(|p| p.as_dvec3());
    let side_a = a.map(|p| sign(orient(b[0], b[1], b[2], p)));
    if side_a.iter().all(|&s| s > 0) || side_a.iter().all(|&s| s < 0) {
        return false;
    }
    let side_b = b.map(|p| sign(orient(a[0], a[1], a[2], p)));
    if side_b.iter().all(|&s| s > 0) || side_b.iter().all(|&s| s < 0) {
        return false;
    }
    let a_flat = is_degenerate(a);
    let b_flat = is_degenerate(b);
    if a_flat && b_flat {
        // Two zero-area triangles (segments or points): out of scope, `validate` and the
        // quality checks report degenerate faces on their own.
        return false;
    }
    if side_a.iter().all(|&s| s == 0) && !b_flat {
        return coplanar_intersect(a, b, b);
    }
    if side_b.iter().all(|&s| s == 0) && !a_flat {
        return coplanar_intersect(a, b, a);
    }
    let edges = |t: [DVec3; 3]| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])];
    (!b_flat
        && edges(a)
            .iter()
            .any(|&(p, q)| segment_meets_triangle(p, q, b)))
        || (!a_flat
            && edges(b)
                .iter()
                .any(|&(p, q)| segment_meets_triangle(p, q, a)))
}

/// Collinear (or coincident) corners: orient2d is zero in every axis-aligned projection.
fn is_degenerate(t: [DVec3; 3]) -> bool {
    (0..3).all(|axis| project_orient(t[0], t[1], t[2], axis) == 0.0)
}

/// Segment `pq` against a non-degenerate triangle `t`, both closed.
fn segment_meets_triangle(p: DVec3, q: DVec3, t: [DVec3; 3]) -> bool {
    let sp = sign(orient(t[0], t[1], t[2], p));
    let sq = sign(orient(t[0], t[1], t[2], q));
    if sp * sq > 0 {
        return false;
    }
    if sp == 0 && sq == 0 {
        return coplanar_segment_triangle(p, q, t);
    }
    // The segment crosses the plane once; the crossing is inside the triangle when the line pq
    // passes on the same side of all three edges (Plücker signs; zero means on an edge).
    let s = [
        sign(orient(p, q, t[0], t[1])),
        sign(orient(p, q, t[1], t[2])),
        sign(orient(p, q, t[2], t[0])),
    ];
    !(s.contains(&1) && s.contains(&-1))
}

/// The axis to drop so that the plane of `t` projects without collapsing.
fn projection_axis(t: [DVec3; 3]) -> usize {
    let n = (t[1] - t[0]).cross(t[2] - t[0]).abs();
    if n.x >= n.y && n.x >= n.z {
        0
    } else if n.y >= n.z {
        1
    } else {
        2
    }
}

fn drop_axis(p: DVec3, axis: usize) -> Coord<f64> {
    match axis {
        0 => Coord { x: p.y, y: p.z },
        1 => Coord { x: p.z, y: p.x },
        _ => Coord { x: p.x, y: p.y },
    }
}

fn project_orient(a: DVec3, b: DVec3, c: DVec3, axis: usize) -> f64 {
    orient2d(drop_axis(a, axis), drop_axis(b, axis), drop_axis(c, axis))
}

/// Both triangles lie in one plane (that of `reference`, which is not degenerate).
fn coplanar_intersect(a: [DVec3; 3], b: [DVec3; 3], reference: [DVec3; 3]) -> bool {
    let axis = projection_axis(reference);
    let pa = a.map(|p| drop_axis(p, axis));
    let pb = b.map(|p| drop_axis(p, axis));
    let edges = |t: [Coord<f64>; 3]| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])];
    edges(pa).iter().any(|&(p, q)| {
        edges(pb)
            .iter()
            .any(|&(r, s)| segments_intersect_2d(p, q, r, s))
    }) || point_in_triangle_2d(pa[0], pb)
        || point_in_triangle_2d(pb[0], pa)
}

fn coplanar_segment_triangle(p: DVec3, q: DVec3, t: [DVec3; 3]) -> bool {
    let axis = projection_axis(t);
    let (pp, pq) = (drop_axis(p, axis), drop_axis(q, axis));
    let pt = t.map(|x| drop_axis(x, axis));
    point_in_triangle_2d(pp, pt)
        || point_in_triangle_2d(pq, pt)
        || [(pt[0], pt[1]), (pt[1], pt[2]), (pt[2], pt[0])]
            .iter()
            .any(|&(r, s)| segments_intersect_2d(pp, pq, r, s))
}

fn orient_sign_2d(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>) -> i8 {
    sign(orient2d(a, b, c))
}

fn point_in_triangle_2d(p: Coord<f64>, t: [Coord<f64>; 3]) -> bool {
    let s = [
        orient_sign_2d(t[0], t[1], p),
        orient_sign_2d(t[1], t[2], p),
        orient_sign_2d(t[2], t[0], p),
    ];
    !(s.contains(&1) && s.contains(&-1))
}

fn on_segment_2d(p: Coord<f64>, q: Coord<f64>, r: Coord<f64>) -> bool {
    // r is collinear with pq: inside the closed box of pq means on the segment.
    r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
}

fn segments_intersect_2d(p: Coord<f64>, q: Coord<f64>, r: Coord<f64>, s: Coord<f64>) -> bool {
    let d1 = orient_sign_2d(r, s, p);
    let d2 = orient_sign_2d(r, s, q);
    let d3 = orient_sign_2d(p, q, r);
    let d4 = orient_sign_2d(p, q, s);
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    (d1 == 0 && on_segment_2d(r, s, p))
        || (d2 == 0 && on_segment_2d(r, s, q))
        || (d3 == 0 && on_segment_2d(p, q, r))
        || (d4 == 0 && on_segment_2d(p, q, s))
}

/// True when two triangles that share one or two vertices (given by `ids`) meet anywhere
/// beyond what they share: a fold that the pair test, which skips neighbours, cannot see.
///
/// Sharing one vertex `v`: both triangles contain `v`, so any further common point gives a
/// common segment from `v`, which ends on the far edge of one of them inside the other; the
/// far-edge tests are therefore complete. Sharing an edge: only coplanar triangles on the same
/// side of it overlap.
pub fn neighbours_overlap(a: [Vec3; 3], a_ids: [u32; 3], b: [Vec3; 3], b_ids: [u32; 3]) -> bool {
    let mut shared = [0usize; 3];
    let mut count = 0;
    for (i, id) in a_ids.iter().enumerate() {
        if b_ids.contains(id) {
            shared[count] = i;
            count += 1;
        }
    }
    match count {
        1 => {
            let i = shared[0];
            let j = (0..3).find(|&j| b_ids[j] == a_ids[i]).unwrap_or(0);
            let (a_far, b_far) = (
                [a[(i + 1) % 3], a[(i + 2) % 3]],
                [b[(j + 1) % 3], b[(j + 2) % 3]],
            );
            !super::separation::surely_apart_at_shared_vertex(a[i], a_far, b_far)
                && overlap_beyond_vertex(a, i, b, j)
        }
        2 => {
            let shared = &shared[..2];
            let da = a.map(|p| p.as_dvec3());
            let db = b.map(|p| p.as_dvec3());
            let far_a = (0..3).find(|i| !shared.contains(i)).unwrap_or(0);
            let far_b = (0..3).find(|&j| !a_ids.contains(&b_ids[j])).unwrap_or(0);
            let (p, q) = (da[shared[0]], da[shared[1]]);
            if orient(p, q, da[far_a], db[far_b]) != 0.0 || is_degenerate(da) {
                return false;
            }
            let axis = projection_axis(da);
            let side = |x: DVec3| {
                orient_sign_2d(drop_axis(p, axis), drop_axis(q, axis), drop_axis(x, axis))
            };
            side(da[far_a]) * side(db[far_b]) > 0
        }
        _ => false,
    }
}

/// Exact test for triangles sharing only the vertex `a[i]` = `b[j]`: does either far edge meet
/// the other triangle?
fn overlap_beyond_vertex(a: [Vec3; 3], i: usize, b: [Vec3; 3], j: usize) -> bool {
    let da = a.map(|p| p.as_dvec3());
    let db = b.map(|p| p.as_dvec3());
    let (a1, a2) = (da[(i + 1) % 3], da[(i + 2) % 3]);
    let (b1, b2) = (db[(j + 1) % 3], db[(j + 2) % 3]);
    (!is_degenerate(db) && segment_meets_triangle(a1, a2, db))
        || (!is_degenerate(da) && segment_meets_triangle(b1, b2, da))
}

#[cfg(test)]
mod tests {
    use super::super::separation::surely_apart_at_shared_vertex;
    use super::*;
    use proptest::prelude::*;

    fn point() -> impl Strategy<Value = Vec3> {
        (-1.0f32..1.0, -1.0f32..1.0, -0.3f32..0.3).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]
        /// The fast filter never hides an overlap the exact test finds: random pairs of faces
        /// around a shared vertex, flat-ish (fans of a surface) and folded.
        #[test]
        fn shared_vertex_filter_is_conservative(
            p in point(), a1 in point(), a2 in point(), b1 in point(), b2 in point(),
            flatten in prop::bool::ANY,
        ) {
            let squash = |v: Vec3| if flatten { Vec3::new(v.x, v.y, v.z * 1e-3) } else { v };
            let (p, a1, a2, b1, b2) = (squash(p), squash(a1), squash(a2), squash(b1), squash(b2));
            let (a, b) = ([p, a1, a2], [p, b1, b2]);
            if surely_apart_at_shared_vertex(p, [a1, a2], [b1, b2]) {
                prop_assert!(!overlap_beyond_vertex(a, 0, b, 0));
            }
            prop_assert_eq!(
                neighbours_overlap(a, [0, 1, 2], b, [0, 3, 4]),
                overlap_beyond_vertex(a, 0, b, 0)
            );
        }
    }

    /// A fan of six faces around a vertex on a flat sheet: the filter settles every pair that
    /// shares only the centre.
    #[test]
    fn flat_fan_pairs_are_settled_by_the_filter() {
        let ring: Vec<Vec3> = (0..6)
            .map(|k| {
                let t = k as f32 * std::f32::consts::TAU / 6.0;
                Vec3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        for i in 0..6 {
            for k in 2..5 {
                let j = (i + k) % 6;
                let a = [ring[i], ring[(i + 1) % 6]];
                let b = [ring[j], ring[(j + 1) % 6]];
                assert!(surely_apart_at_shared_vertex(Vec3::ZERO, a, b));
                assert!(!overlap_beyond_vertex(
                    [Vec3::ZERO, a[0], a[1]],
                    0,
                    [Vec3::ZERO, b[0], b[1]],
                    0
                ));
            }
        }
    }
}
