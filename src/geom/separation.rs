//! A fast, conservative filter in front of the exact triangle–triangle test: the separating axis
//! test in f64 with a margin far above its rounding error. When it says "apart", the triangles
//! are apart; otherwise the exact predicates decide. Near-coplanar neighbours on a flat sheet —
//! the common case in the collision backstop — are settled here instead of in the slow exact path.

use glam::{DVec3, Vec3};

/// True only when some axis separates the triangles by more than rounding could hide.
pub fn surely_disjoint(a: [Vec3; 3], b: [Vec3; 3]) -> bool {
    let a = a.map(|p| p.as_dvec3());
    let b = b.map(|p| p.as_dvec3());
    let scale = a
        .iter()
        .chain(b.iter())
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    let edges_a = [a[1] - a[0], a[2] - a[1], a[0] - a[2]];
    let edges_b = [b[1] - b[0], b[2] - b[1], b[0] - b[2]];
    let separated = |axis: DVec3| {
        let length = axis.length();
        if length == 0.0 {
            return false;
        }
        // Projections carry relative error ~1e-15 of scale·length; demand far more.
        let margin = 1e-9 * scale * length;
        let (a_lo, a_hi) = project(&a, axis);
        let (b_lo, b_hi) = project(&b, axis);
        a_hi + margin < b_lo || b_hi + margin < a_lo
    };
    if separated(edges_a[0].cross(edges_a[1])) || separated(edges_b[0].cross(edges_b[1])) {
        return true;
    }
    for ea in &edges_a {
        for eb in &edges_b {
            if separated(ea.cross(*eb)) {
                return true;
            }
        }
    }
    // Coplanar pairs: the in-plane edge normals.
    let normal = edges_a[0].cross(edges_a[1]);
    edges_a
        .iter()
        .chain(edges_b.iter())
        .any(|e| separated(normal.cross(*e)))
}

fn project(t: &[DVec3; 3], axis: DVec3) -> (f64, f64) {
    let d = t.map(|p| p.dot(axis));
    (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
}

/// True only when two triangles that share the vertex `p` — the others being `(a1, a2)` and
/// `(b1, b2)` — surely meet nowhere else: seen along a direction both face, their wedges at `p`
/// lie on either side of a line through `p`, by more than rounding could hide.
///
/// Why that suffices: if the projections meet only at `p`, a common point projects onto `p`, so
/// it lies on the line through `p` along the view direction; a triangle whose projection has area
/// meets that line only at `p`. This settles the fans of a smooth surface (every pair of faces
/// around a vertex) without the exact predicates, which near-coplanar fans send down their slow
/// path.
pub fn surely_apart_at_shared_vertex(p: Vec3, a: [Vec3; 2], b: [Vec3; 2]) -> bool {
    let p = p.as_dvec3();
    let [u1, u2] = a.map(|x| x.as_dvec3() - p);
    let [w1, w2] = b.map(|x| x.as_dvec3() - p);
    let (na, nb) = (u1.cross(u2), w1.cross(w2));
    let (la, lb) = (na.length_squared(), nb.length_squared());
    // A view both triangles face: the sum of their unit normals, scaled by |na|²·|nb|² to stay
    // free of square roots. Folded-back pairs (facing apart) are left to the exact test.
    let view = na * lb + nb * la;
    let (fa, fb) = (na.dot(view), nb.dot(view));
    // (Each is |n|²·(|m|² + n·m) for the two normals: rounding is far below the margin.)
    if fa <= 1e-9 * la * lb || fb <= 1e-9 * la * lb {
        return false;
    }
    // Seen along `view`, the side of x from the line through p along r: det(r, x, view), the 2-D
    // cross product of their projections (times |view|). Both wedges turn positively
    // (det(u1, u2, view) = fa > 0 and det(w1, w2, view) = fb > 0).
    let side = |r: DVec3, x: DVec3| r.cross(x).dot(view);
    let (s11, s12, s21, s22) = (side(u1, w1), side(u1, w2), side(u2, w1), side(u2, w2));
    let scale = [u1, u2, w1, w2]
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs().max_element()));
    let margin = 1e-9 * scale * scale * view.abs().max_element();
    // Two convex wedges with a common apex are apart exactly when a line along one of their four
    // sides separates them: along u1 (A on its left) B must lie right, along u2 (A right) B left,
    // and likewise for w1 and w2 with A.
    (s11 < -margin && s12 < -margin)
        || (s21 > margin && s22 > margin)
        || (s11 > margin && s21 > margin)
        || (s12 < -margin && s22 < -margin)
}
