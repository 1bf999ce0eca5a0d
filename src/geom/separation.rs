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
    let [a1, a2] = a.map(|x| x.as_dvec3() - p);
    let [b1, b2] = b.map(|x| x.as_dvec3() - p);
    let (na, nb) = (a1.cross(a2), b1.cross(b2));
    let (la, lb) = (na.length(), nb.length());
    if la == 0.0 || lb == 0.0 {
        return false;
    }
    let (na, nb) = (na / la, nb / lb);
    // A view both triangles face (folded-back pairs are left to the exact test).
    if na.dot(nb) < -0.5 {
        return false;
    }
    let view = (na + nb).normalize();
    let e1 = view.any_orthonormal_vector();
    let e2 = view.cross(e1);
    let flat = |x: DVec3| (x.dot(e1), x.dot(e2));
    let [u1, u2, w1, w2] = [a1, a2, b1, b2].map(flat);
    let cross = |r: (f64, f64), x: (f64, f64)| r.0 * x.1 - r.1 * x.0;
    let scale = [a1, a2, b1, b2]
        .iter()
        .fold(0.0f64, |m, x| m.max(x.length()));
    let margin = 1e-9 * scale * scale;
    // Both projections have area: each triangle meets the view line through p only at p.
    if cross(u1, u2).abs() <= margin || cross(w1, w2).abs() <= margin {
        return false;
    }
    // Two convex wedges with a common apex are apart exactly when a line along one of their
    // four sides separates them.
    let separates = |r: (f64, f64), same: [(f64, f64); 2], other: [(f64, f64); 2]| {
        let s = same.map(|x| cross(r, x));
        let o = other.map(|x| cross(r, x));
        (s.iter().all(|&v| v >= -margin) && o.iter().all(|&v| v < -margin))
            || (s.iter().all(|&v| v <= margin) && o.iter().all(|&v| v > margin))
    };
    separates(u1, [u1, u2], [w1, w2])
        || separates(u2, [u1, u2], [w1, w2])
        || separates(w1, [w1, w2], [u1, u2])
        || separates(w2, [w1, w2], [u1, u2])
}
