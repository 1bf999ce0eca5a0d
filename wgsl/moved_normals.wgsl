// The normals a step's moves changed, recomputed where the step ran so that the next sample of
// a stroke recorded in the same submission selects and deforms on them (the pipeline's
// `recompute_normals_at` after a sample, on the GPU). A moved vertex turns every face around
// it, and so the normal of every corner of those faces: one invocation per slot of the moving
// list, which recomputes all of them when the entry's vertex is no longer at its start. Vacant
// slots and still vertices write nothing. A corner shared by several moved vertices is written
// by each, the same value each time (shared/normals reads positions only).
// CPU mirror: src/cpu/moved_normals.rs.

#import shared/grid
#import shared/mesh
#import shared/moves
#import shared/pages
#import shared/order_free
#import shared/normals
#paged topology 1

// Host struct: `NormalParams`, `count` being the slots of the moving list.
struct NormalParams {
    count: u32,
    vertex_rows_base: u32,
    _pad0: u32,
    _pad1: u32,
}

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: NormalParams;
// Positions after the step, packed x, y, z.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> moving: array<MovingVertex>;
// Packed x, y, z per vertex of the mesh; only the corners of faces around moved vertices are
// written.
@group(0) @binding(3) var<storage, read_write> normals: array<f32>;

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
    let entry = moving[i];
    if entry.vertex == INVALID || all(position(entry.vertex) == entry.start) {
        return;
    }
    let row = params.vertex_rows_base + 2u * entry.vertex;
    let first = topology(row);
    let last = first + topology(row + 1u);
    for (var k = first; k < last; k++) {
        let f = topology(k);
        for (var corner = 0u; corner < 3u; corner++) {
            let u = topology(4u * f + corner);
            let n = vertex_normal(u, params.vertex_rows_base);
            normals[3u * u] = n.x;
            normals[3u * u + 1u] = n.y;
            normals[3u * u + 2u] = n.z;
        }
    }
}
