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
