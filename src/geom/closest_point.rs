use glam::Vec3;

/// The point of triangle `abc` closest to `p`, by Voronoi regions (Ericson §5.1.5). Degenerate
/// triangles fall through to an edge or vertex region and stay finite.
///
/// The corners are taken in a canonical order first ([`canonical_corners`]), so the result does
/// not depend on the order they are given in, and a reflection in a coordinate plane through the
/// origin reflects it exactly: a mirrored mesh's faces list their corners in reversed order, and
/// symmetric sculpting must clamp both sides alike to the bit.
pub fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let [a, b, c] = canonical_corners([a, b, c]);
    closest_point_in_order(p, a, b, c)
}

/// The corners sorted by |x|, then |y|, then |z| (keys a reflection in x = 0, y = 0 or z = 0
/// keeps); corners with equal keys keep their order.
fn canonical_corners([mut a, mut b, mut c]: [Vec3; 3]) -> [Vec3; 3] {
    let before = |p: Vec3, q: Vec3| {
        let (p, q) = (p.abs(), q.abs());
        (p.x, p.y, p.z) < (q.x, q.y, q.z)
    };
    if before(b, a) {
        std::mem::swap(&mut a, &mut b);
    }
    if before(c, b) {
        std::mem::swap(&mut b, &mut c);
    }
    if before(b, a) {
        std::mem::swap(&mut a, &mut b);
    }
    [a, b, c]
}

fn closest_point_in_order(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w;
    }
    let denom = va + vb + vc;
    if denom.abs() <= f32::MIN_POSITIVE {
        // Collinear corners that slipped past the edge regions: the nearest corner is safe.
        return [a, b, c]
            .into_iter()
            .min_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)))
            .unwrap_or(a);
    }
    let inv = 1.0 / denom;
    let v = vb * inv;
    let w = vc * inv;
    a + ab * v + ac * w
}

/// Distance from `p` to the triangle `[a, b, c]`.
#[inline]
pub fn point_triangle_distance(p: Vec3, [a, b, c]: [Vec3; 3]) -> f32 {
    closest_point_on_triangle(p, a, b, c).distance(p)
}

/// Squared distance from `p` to triangle `abc`.
pub fn point_triangle_distance_squared(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    closest_point_on_triangle(p, a, b, c).distance_squared(p)
}
