// Exact point–triangle geometry, as `src/geom/closest_point.rs` computes it: the same Voronoi
// region tests in the same order, so f32 results agree with the CPU to a few ulps (a GPU may
// still fuse multiply-adds the CPU rounds twice).

// Smallest normal f32 (`f32::MIN_POSITIVE`).
const MIN_POSITIVE_F32: f32 = 1.17549435e-38;

// The point of triangle abc closest to p (Ericson §5.1.5). Degenerate triangles fall through
// to an edge or vertex region and stay finite.
fn closest_point_on_triangle(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
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
    if abs(denom) <= MIN_POSITIVE_F32 {
        // Collinear corners that slipped past the edge regions: the nearest corner (the first
        // of equals, as the CPU's `min_by`).
        var nearest = a;
        var best = dot(a - p, a - p);
        if dot(b - p, b - p) < best {
            nearest = b;
            best = dot(b - p, b - p);
        }
        if dot(c - p, c - p) < best {
            nearest = c;
        }
        return nearest;
    }
    let inv = 1.0 / denom;
    let v = vb * inv;
    let w = vc * inv;
    return a + ab * v + ac * w;
}

// Distance from p to triangle abc, as glam's `distance` (square root of the dot product).
fn distance_to_triangle(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    let offset = closest_point_on_triangle(p, a, b, c) - p;
    return sqrt(dot(offset, offset));
}
