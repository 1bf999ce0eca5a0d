// Exact point–triangle geometry, as `src/geom/closest_point.rs` computes it: the same Voronoi
// region tests in the same order, so f32 results agree with the CPU to a few ulps (a GPU may
// still fuse multiply-adds the CPU rounds twice).

// Smallest normal f32 (`f32::MIN_POSITIVE`).
const MIN_POSITIVE_F32: f32 = 1.17549435e-38;

// Whether corner p comes before q in the canonical order: by |x|, then |y|, then |z| (keys a
// reflection in x = 0, y = 0 or z = 0 keeps), as `canonical_corners` in
// src/geom/closest_point.rs.
fn corner_before(p: vec3<f32>, q: vec3<f32>) -> bool {
    let s = abs(p);
    let t = abs(q);
    return s.x < t.x || (s.x == t.x && (s.y < t.y || (s.y == t.y && s.z < t.z)));
}

// The point of triangle abc closest to p (Ericson §5.1.5), its corners taken in the canonical
// order first, so that a mirrored face gets the mirrored point to the bit. Degenerate triangles
// fall through to an edge or vertex region and stay finite.
fn closest_point_on_triangle(p: vec3<f32>, a_in: vec3<f32>, b_in: vec3<f32>, c_in: vec3<f32>) -> vec3<f32> {
    var a = a_in;
    var b = b_in;
    var c = c_in;
    if corner_before(b, a) {
        let t = a;
        a = b;
        b = t;
    }
    if corner_before(c, b) {
        let t = b;
        b = c;
        c = t;
    }
    if corner_before(b, a) {
        let t = a;
        a = b;
        b = t;
    }
    return closest_point_in_order(p, a, b, c);
}

//
// One exit, the regions as an else-if chain: Mesa 22.3's lavapipe miscompiled early returns
// from this function once it was inlined into the proximity kernel's loops (later faces were
// skipped). Every quantity is the same expression as on the CPU, so results are unchanged.
fn closest_point_in_order(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    let bp = p - b;
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    let cp = p - c;
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    let vc = d1 * d4 - d3 * d2;
    let vb = d5 * d2 - d1 * d6;
    let va = d3 * d6 - d5 * d4;
    let denom = va + vb + vc;
    var closest = a;
    if d1 <= 0.0 && d2 <= 0.0 {
        closest = a;
    } else if d3 >= 0.0 && d4 <= d3 {
        closest = b;
    } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        closest = a + ab * (d1 / (d1 - d3));
    } else if d6 >= 0.0 && d5 <= d6 {
        closest = c;
    } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        closest = a + ac * (d2 / (d2 - d6));
    } else if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        closest = b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    } else if abs(denom) <= MIN_POSITIVE_F32 {
        // Collinear corners that slipped past the edge regions: the nearest corner (the first
        // of equals, as the CPU's `min_by`).
        var best = dot(a - p, a - p);
        if dot(b - p, b - p) < best {
            closest = b;
            best = dot(b - p, b - p);
        }
        if dot(c - p, c - p) < best {
            closest = c;
        }
    } else {
        let inv = 1.0 / denom;
        closest = a + ab * (vb * inv) + ac * (vc * inv);
    }
    return closest;
}

// Distance from p to triangle abc, as glam's `distance` (square root of the dot product).
fn distance_to_triangle(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    let offset = closest_point_on_triangle(p, a, b, c) - p;
    return sqrt(dot(offset, offset));
}
