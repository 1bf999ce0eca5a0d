// A vertex normal as `Mesh::recompute_normals_at` computes it (`fan_normal` in
// src/geom/order_free.rs): each incident face's cross product seen from the vertex,
// `(p - v) x (q - v)`, summed order-free (shared/order_free, imported before this), so that a
// mirrored mesh gets mirrored normals to the bit; the integer sum normalized; +Z where it
// vanishes, a term is not finite, or every term is below the smallest normal f32. Face normals
// are not stored anywhere (the CPU recomputes them inline too). The kernel importing this
// provides `position(v)` and the paged `topology(i)` (src/gpu/topology.rs: faces as
// (a, b, c, layer), then the vertex→faces rows' (start, length) entries from
// `vertex_rows_base`, and the rows). CPU mirror: `vertex_normal` in src/cpu/vertex_normals.rs.

// Face `f`'s cross product at its corner `v`.
fn corner_cross_at(f: u32, v: u32) -> vec3<f32> {
    let a = topology(4u * f);
    let b = topology(4u * f + 1u);
    let c = topology(4u * f + 2u);
    var p = b;
    var q = c;
    if v == b {
        p = c;
        q = a;
    } else if v == c {
        p = a;
        q = b;
    }
    let o = position(v);
    return cross(position(p) - o, position(q) - o);
}

fn vertex_normal(v: u32, vertex_rows_base: u32) -> vec3<f32> {
    let up = vec3<f32>(0.0, 0.0, 1.0);
    let row = vertex_rows_base + 2u * v;
    let first = topology(row);
    let last = first + topology(row + 1u);
    var largest = 0.0;
    for (var k = first; k < last; k++) {
        let term = corner_cross_at(topology(k), v);
        if !order_free_finite(term) {
            return up;
        }
        largest = max(largest, order_free_largest(term));
    }
    if largest < ORDER_FREE_MIN_F32 {
        return up;
    }
    let exponent = order_free_exponent(largest, last - first);
    var sum = vec3<i32>(0);
    for (var k = first; k < last; k++) {
        sum += order_free_term(corner_cross_at(topology(k), v), exponent);
    }
    let total = vec3<f32>(sum);
    // glam's try_normalize: the reciprocal of sqrt(dot) must be finite and positive.
    let rcp = 1.0 / sqrt(dot(total, total));
    if rcp <= ORDER_FREE_MAX_F32 && rcp > 0.0 {
        return total * rcp;
    }
    return up;
}
