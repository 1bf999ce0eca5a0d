// Vertex normals of the region a step touched, as `Mesh::recompute_normals_at` computes them:
// the sum of the incident faces' cross products (area-weighted), in fan order, normalized; +Z
// where the sum vanishes or is not finite. One invocation per listed vertex, each writing only
// its own normal, so a vertex listed twice writes the same value twice. Face normals are not
// stored anywhere (the CPU recomputes them inline too), so no separate face pass is needed.
// CPU mirror: src/cpu/vertex_normals.rs.

#import shared/grid
#import shared/pages
#paged topology 1

struct NormalParams {
    // Vertices listed.
    count: u32,
    // Where the per-vertex (start, length) entries of the vertex→faces rows begin in
    // `topology`.
    vertex_rows_base: u32,
    _pad0: u32,
    _pad1: u32,
}

const WORKGROUP_SIZE: u32 = 64u;
// Largest finite f32: WGSL has no isfinite.
const MAX_F32: f32 = 3.40282347e38;

@group(0) @binding(0) var<uniform> params: NormalParams;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> vertices: array<u32>;
// Packed x, y, z per vertex of the mesh; only the listed ones are written.
@group(0) @binding(3) var<storage, read_write> normals: array<f32>;
// Paged (shared/pages.wgsl), group 1: `topology(i)`, src/gpu/topology.rs: faces as
// (a, b, c, layer), then the vertex→faces rows' (start, length) entries and the rows.

fn position(v: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i >= params.count {
        return;
    }
    let v = vertices[i];
    let row = params.vertex_rows_base + 2u * v;
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
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if rcp <= MAX_F32 && rcp > 0.0 {
        n = sum * rcp;
    }
    normals[3u * v] = n.x;
    normals[3u * v + 1u] = n.y;
    normals[3u * v + 2u] = n.z;
}
