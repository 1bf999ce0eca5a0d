// The longest edge of the faces around the vertices a sample moved, folded into the run's edge
// bound (`GateStatus::edge`, shared/gate) — the pipeline's own bound, `max_edge` grown by the
// longest edge of every face its moves turned, kept on the GPU — so that `sample_gate` stops a
// run at the first sample whose passes were sized for shorter edges than the samples before it
// left. One invocation per slot of the moving list; vacant slots and still vertices do nothing.
// `distance` may round differently from the host's; the host checks the pipeline's own bound
// again when it takes the sample.
// CPU mirror: src/cpu/moved_edges.rs.

#import shared/gate
#import shared/grid
#import shared/mesh
#import shared/moves
#import shared/pages
#paged topology 1

// Host struct: `NormalParams` (the same two words as `moved_normals`: slots of the moving list,
// and where the vertex→faces rows start in `topology`).
struct NormalParams {
    count: u32,
    vertex_rows_base: u32,
    _pad0: u32,
    _pad1: u32,
}

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: NormalParams;
// Positions after the sample's moves, packed x, y, z.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> moving: array<MovingVertex>;
@group(0) @binding(3) var<storage, read_write> status: GateStatus;

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
    var longest = 0.0;
    for (var k = first; k < last; k++) {
        let f = topology(k);
        let a = position(topology(4u * f));
        let b = position(topology(4u * f + 1u));
        let c = position(topology(4u * f + 2u));
        longest = max(longest, max(max(distance(a, b), distance(b, c)), distance(c, a)));
    }
    // Non-negative: its bits order as the lengths do.
    atomicMax(&status.edge, bitcast<u32>(longest));
}
