// Vertex normals of listed vertices (shared/normals: as `Mesh::recompute_normals_at` computes
// them). One invocation per listed vertex, each writing only its own normal, so a vertex listed
// twice writes the same value twice.
// CPU mirror: src/cpu/vertex_normals.rs.

#import shared/grid
#import shared/pages
#import shared/order_free
#import shared/normals
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
    let n = vertex_normal(v, params.vertex_rows_base);
    normals[3u * v] = n.x;
    normals[3u * v + 1u] = n.y;
    normals[3u * v + 2u] = n.z;
}
