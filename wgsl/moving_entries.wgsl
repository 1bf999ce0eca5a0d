// The moving entries of a step (shared/moves) built from the selection list on the GPU, each
// with its vertex's exclusion ring, so that the proximity passes follow `select` and `deform`
// in the same submission (docs/design.md, "A stroke"; on the host, `moving_vertices` in
// src/gpu/proximity.rs builds the same entries). One invocation per slot of the list up to
// `capacity`, the room the passes after it were sized for: slots past the selection's count
// become vacant entries.
//
// The ring — the vertices within graph distance `ring` of the entry's vertex, itself first — is
// grown breadth first over the faces around each vertex (the packed topology's rows: on a
// boundary too, a vertex's faces hold all its neighbours) into the entry's `ring_stride` words
// of `rings`. A ring that does not fit is cut short and counted in `overflows`: the host then
// builds that step's rings itself. A neighbour of a vertex at distance k is at distance k − 1,
// k or k + 1, so membership is looked up from the start of layer k − 1 only: that keeps an
// invocation's loop iterations (rings of three: a few thousand) well below the cap lavapipe
// puts on them (see proximity.wgsl).
// CPU mirror: src/cpu/moving_entries.rs.

#import shared/brush
#import shared/grid
#import shared/mesh
#import shared/moves
#import shared/pages
#paged topology 1

struct EntryParams {
    // Slots of the list covered.
    capacity: u32,
    // Graph distance of the exclusion ring.
    ring: u32,
    // Words per entry in `rings`.
    ring_stride: u32,
    // Where the vertex→faces rows start in `topology`.
    vertex_rows_base: u32,
}

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: EntryParams;
// Packed x, y, z per vertex: the step's start positions.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> layers: array<u32>;
@group(0) @binding(3) var<storage, read> selected: array<SelectedVertex>;
@group(0) @binding(4) var<storage, read> selection_count: u32;
@group(0) @binding(5) var<storage, read_write> moving: array<MovingVertex>;
// Per slot, `ring_stride` words from slot · ring_stride.
@group(0) @binding(6) var<storage, read_write> rings: array<u32>;
// Entries whose ring was cut short.
@group(0) @binding(7) var<storage, read_write> overflows: atomic<u32>;
// Paged (shared/pages.wgsl), group 1: `topology(i)`, the packed topology (src/gpu/topology.rs):
// faces first, four words each (a, b, c, layer); from vertex_rows_base per vertex the absolute
// start and length of its row of face ids.

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i >= params.capacity {
        return;
    }
    let base = i * params.ring_stride;
    if i >= selection_count {
        moving[i] = MovingVertex(vec3<f32>(0.0), INVALID, 0u, base, base, 0u);
        return;
    }
    let v = selected[i].vertex;
    rings[base] = v;
    var len = 1u;
    var cut = false;
    // Layer k (the frontier) starts at `layer`, layer k − 1 at `previous`.
    var previous = 0u;
    var layer = 0u;
    for (var k = 0u; k < params.ring; k++) {
        let frontier_end = len;
        for (var j = layer; j < frontier_end; j++) {
            let row = params.vertex_rows_base + 2u * rings[base + j];
            let first = topology(row);
            let last = first + topology(row + 1u);
            for (var q = first; q < last; q++) {
                let f = topology(q);
                for (var corner = 0u; corner < 3u; corner++) {
                    let w = topology(4u * f + corner);
                    var known = false;
                    for (var m = previous; m < len; m++) {
                        known = known || rings[base + m] == w;
                    }
                    if !known {
                        if len < params.ring_stride {
                            rings[base + len] = w;
                            len++;
                        } else {
                            cut = true;
                        }
                    }
                }
            }
        }
        previous = layer;
        layer = frontier_end;
    }
    if cut {
        atomicAdd(&overflows, 1u);
    }
    let start = vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
    moving[i] = MovingVertex(start, v, layers[v], base, base + len, 0u);
}
