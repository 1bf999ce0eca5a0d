//! `closest_point_on_triangle` is both production code (the collision clamp, the remesher's
//! safety checks) and the brute force other tests compare against, so it gets an oracle of its
//! own that shares none of its arithmetic: the triangle sampled densely by barycentric
//! coordinates in `f64`. The closest sample is at most one grid cell from the true closest
//! point, which bounds the answer from both sides; the answer must also lie on the triangle.
//! A second oracle, also in `f64` and by another route (project onto the plane; if outside,
//! the closest of the three edges' clamped projections), pins the point itself, which the
//! sampled distance alone cannot (moving along an edge near the answer changes the distance
//! only to second order). Query points are drawn by barycentric coordinates from -2 to 3 and
//! an offset along the normal, so every Voronoi region (the face, three edges, three corners)
//! is visited.

use glam::{DVec3, Vec3};
use proptest::prelude::*;
use slayer::geom::closest_point_on_triangle;

/// Grid divisions per side of the sampled triangle.
const DIVISIONS: usize = 240;

/// The distance from `p` to the closest of the triangle's barycentric grid points, in `f64`.
fn sampled_distance(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
    let n = DIVISIONS as f64;
    let mut best = f64::INFINITY;
    for i in 0..=DIVISIONS {
        for j in 0..=DIVISIONS - i {
            let (u, v) = (i as f64 / n, j as f64 / n);
            let q = a + (b - a) * u + (c - a) * v;
            best = best.min(q.distance(p));
        }
    }
    best
}

/// How far `q` is from the triangle's plane, and whether its barycentric coordinates in that
/// plane lie within [-slack, 1 + slack] (least squares in `f64`, independent of the code
/// under test).
fn on_triangle(q: DVec3, [a, b, c]: [DVec3; 3], slack: f64) -> (f64, bool) {
    let (e1, e2, r) = (b - a, c - a, q - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (r1, r2) = (r.dot(e1), r.dot(e2));
    let det = d11 * d22 - d12 * d12;
    let u = (d22 * r1 - d12 * r2) / det;
    let v = (d11 * r2 - d12 * r1) / det;
    let in_plane = a + e1 * u + e2 * v;
    let inside = [u, v, 1.0 - u - v]
        .iter()
        .all(|&w| (-slack..=1.0 + slack).contains(&w));
    (in_plane.distance(q), inside)
}

/// The closest point by projection: onto the plane when that lands inside, else onto the
/// nearest edge (each clamped to its segment).
fn projected(p: DVec3, [a, b, c]: [DVec3; 3]) -> DVec3 {
    let normal = (b - a).cross(c - a).normalize();
    let in_plane = p - normal * (p - a).dot(normal);
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(x, y)| (y - x).cross(in_plane - x).dot(normal) >= 0.0);
    if inside {
        return in_plane;
    }
    let on_segment = |x: DVec3, y: DVec3| {
        let t = ((p - x).dot(y - x) / (y - x).length_squared()).clamp(0.0, 1.0);
        x + (y - x) * t
    };
    [on_segment(a, b), on_segment(b, c), on_segment(c, a)]
        .into_iter()
        .min_by(|q, r| q.distance(p).total_cmp(&r.distance(p)))
        .unwrap()
}

fn point() -> impl Strategy<Value = Vec3> {
    (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Triangles that are not too close to degenerate for the grid to bound the answer: a
/// smallest angle of about a degree or more.
fn triangle() -> impl Strategy<Value = [Vec3; 3]> {
    (point(), point(), point())
        .prop_filter("nearly degenerate", |&(a, b, c)| {
            let area2 = (b - a).cross(c - a).length();
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            longest > 0.05 && area2 > 0.02 * longest * longest
        })
        .prop_map(|(a, b, c)| [a, b, c])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(384))]

    #[test]
    fn the_closest_point_agrees_with_dense_sampling_in_every_region(
        [a, b, c] in triangle(),
        (u, v) in (-2.0f32..3.0, -2.0f32..3.0),
        lift in -1.0f32..1.0,
    ) {
        let normal = (b - a).cross(c - a).normalize();
        let p = a + (b - a) * u + (c - a) * v + normal * lift;
        let q = closest_point_on_triangle(p, a, b, c);
        let tri = [a, b, c].map(|x| x.as_dvec3());
        let (p64, q64) = (p.as_dvec3(), q.as_dvec3());
        let longest = (tri[1] - tri[0]).length().max((tri[2] - tri[1]).length()).max((tri[0] - tri[2]).length());
        // f32 rounding of coordinates around 1, with room for a few operations.
        let eps = 1e-5;
        let found = q64.distance(p64);
        let sampled = sampled_distance(p64, tri);
        // Never farther than some point of the triangle; never closer than the triangle is.
        prop_assert!(found <= sampled + eps, "found {found}, a sample is at {sampled}");
        let cell = longest / DIVISIONS as f64;
        prop_assert!(found >= sampled - cell - eps, "found {found}, closer than the triangle ({sampled} - {cell})");
        // The projection agrees with the samples, and the answer with the projection.
        let exact = projected(p64, tri);
        let by_projection = exact.distance(p64);
        prop_assert!(by_projection <= sampled + eps && by_projection >= sampled - cell - eps);
        prop_assert!(q64.distance(exact) <= 1e-4, "answer {q64} is {} from {exact}", q64.distance(exact));
        let (off_plane, inside) = on_triangle(q64, tri, 1e-4);
        prop_assert!(off_plane <= eps && inside, "answer off the triangle: {off_plane} from its plane, inside {inside}");
    }
}
