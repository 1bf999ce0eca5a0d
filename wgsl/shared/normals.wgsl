// A vertex normal as `Mesh::recompute_normals_at` computes it: the sum of the incident faces'
// cross products (area-weighted), in fan order, normalized; +Z where the sum vanishes or is not
// finite. Face normals are not stored anywhere (the CPU recomputes them inline too). The kernel
// importing this provides `position(v)` and the paged `topology(i)` (src/gpu/topology.rs:
// faces as (a, b, c, layer), then the vertex→faces rows' (start, length) entries from
// `vertex_rows_base`, and the rows). CPU mirror: `vertex_normal` in src/cpu/vertex_normals.rs.

// Largest finite f32: WGSL has no isfinite.
const MAX_F32: f32 = 3.40282347e38;

fn vertex_normal(v: u32, vertex_rows_base: u32) -> vec3<f32> {
    let row = vertex_rows_base + 2u * v;
    let first = topology(row);
    let last = first + topology(row + 1u);
    var sum = vec3<f32>(0.0);
    for (var k = first; k < last; k++) {
        let f = topology(k);
        let a = position(topology(4u * f));
        let b = position(topology(4u * f + 1u));
        let c = position(topology(4u * f + 2u));
        sum += cross(b - a, c - a);
    }
    // glam's try_normalize: the reciprocal of sqrt(dot) must be finite and positive.
    let rcp = 1.0 / sqrt(dot(sum, sum));
    if rcp <= MAX_F32 && rcp > 0.0 {
        return sum * rcp;
    }
    return vec3<f32>(0.0, 0.0, 1.0);
}
