// Writes a step's moves into the positions, around the proximity passes (docs/design.md, "A stroke"
// "collide"), so that a whole Jacobi loop runs on the GPU with one read-back at its end.
// One invocation per entry of the moving list; `mode` says which write:
//
// - PLACE: every vertex to its brush target (`collide` writes the targets in before the first
//   pass), its mark cleared.
// - PULL: where the pass pulled the vertex back (a nonzero amount in `pulls`), to
//   start + (x − start)·t, as `pull_back` computes it, and marked: the next pass tests only
//   faces with a marked vertex, the faces the CPU's `changed` holds. Where it did not, the mark
//   is cleared. Any pull stores the next pass's invocation count in `next_count`, which
//   `dispatch_args` turns into its size: a pass that pulled nothing ends the loop. The amount
//   is consumed (zeroed) for the next pass.
// - PULL_LAST: as PULL, but out of passes: what still collides goes back to its start.
// - GATHER: the final position of every entry into `finals` (what the host reads back), and
//   the marks cleared for the next step.
// - MARK_MOVED: after GATHER, each entry's vertex marked with the entry + 1 where the step
//   moved it (zero where not): the map the backstop filter reads.
// - CLEAR: the marks cleared (after the backstop filter).
//
// Entries name distinct vertices, so no two invocations write the same slot; vacant entries
// (shared/moves) write nothing.
// CPU mirror: src/cpu/apply_moves.rs.

#import shared/grid
#import shared/mesh
#import shared/moves

struct ApplyParams {
    // Entries in `moving`.
    count: u32,
    mode: u32,
    // What a pull stores in `next_count`: the next proximity pass's invocations.
    next_invocations: u32,
    _pad: u32,
}

const MODE_PLACE: u32 = 0u;
const MODE_PULL: u32 = 1u;
const MODE_PULL_LAST: u32 = 2u;
const MODE_GATHER: u32 = 3u;
const MODE_MARK_MOVED: u32 = 4u;
const MODE_CLEAR: u32 = 5u;
const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: ApplyParams;
@group(0) @binding(1) var<storage, read> moving: array<MovingVertex>;
// Brush targets, packed x, y, z, one per entry.
@group(0) @binding(2) var<storage, read> targets: array<f32>;
// Per entry: the proximity pass's pull-back amount, 65536 − 65536·t, or zero.
@group(0) @binding(3) var<storage, read_write> pulls: array<u32>;
// Packed x, y, z per vertex.
@group(0) @binding(4) var<storage, read_write> positions: array<f32>;
// Per vertex: 1 when pulled back in the last pass.
@group(0) @binding(5) var<storage, read_write> marks: array<u32>;
@group(0) @binding(6) var<storage, read_write> next_count: atomic<u32>;
// Final positions, packed x, y, z, one per entry.
@group(0) @binding(7) var<storage, read_write> finals: array<f32>;

const PULL_SCALE: f32 = 65536.0;

fn position(v: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}

fn set_position(v: u32, p: vec3<f32>) {
    positions[3u * v] = p.x;
    positions[3u * v + 1u] = p.y;
    positions[3u * v + 2u] = p.z;
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
    let v = entry.vertex;
    if v == INVALID {
        return;
    }
    switch params.mode {
        case MODE_PLACE: {
            set_position(v, vec3<f32>(targets[3u * i], targets[3u * i + 1u], targets[3u * i + 2u]));
            marks[v] = 0u;
            pulls[i] = 0u;
        }
        case MODE_PULL, MODE_PULL_LAST: {
            let pull = pulls[i];
            if pull != 0u {
                if params.mode == MODE_PULL_LAST {
                    set_position(v, entry.start);
                } else {
                    let t = f32(65536u - pull) / PULL_SCALE;
                    set_position(v, entry.start + (position(v) - entry.start) * t);
                }
                marks[v] = 1u;
                pulls[i] = 0u;
                atomicStore(&next_count, params.next_invocations);
            } else {
                marks[v] = 0u;
            }
        }
        case MODE_MARK_MOVED: {
            marks[v] = select(0u, i + 1u, any(position(v) != entry.start));
        }
        case MODE_CLEAR: {
            marks[v] = 0u;
        }
        default: {
            let p = position(v);
            finals[3u * i] = p.x;
            finals[3u * i + 1u] = p.y;
            finals[3u * i + 2u] = p.z;
            marks[v] = 0u;
            pulls[i] = 0u;
        }
    }
}
