// The gate of a run of samples recorded ahead (shared/gate), in three stages the host records
// around each sample's passes: GATE_OPEN after `select`, GATE_DECIDE after `longest_move`
// (the edges the samples before left measured by their `moved_edges`),
// GATE_VACATE before `apply_moves` places anything. The decision is taken by one invocation
// and read by the next dispatch, so every slot sees the same verdict.
// CPU mirror: src/cpu/sample_gate.rs.

#import shared/gate
#import shared/grid
#import shared/mesh
#import shared/moves

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: GateParams;
@group(0) @binding(1) var<storage, read_write> selection_count: u32;
// Entries whose exclusion ring `moving_entries` cut short.
@group(0) @binding(2) var<storage, read> ring_overflows: u32;
@group(0) @binding(3) var<storage, read_write> moving: array<MovingVertex>;
@group(0) @binding(4) var<storage, read_write> status: GateStatus;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    switch params.stage {
        case GATE_OPEN: {
            if i == 0u {
                atomicStore(&status.longest, 0u);
                if status.stopped != 0u {
                    selection_count = 0u;
                }
            }
        }
        case GATE_DECIDE: {
            if i == 0u {
                var why = 0u;
                if status.stopped != 0u {
                    why |= STOPPED_EARLIER;
                }
                if selection_count > params.capacity {
                    why |= STOPPED_SELECTION;
                }
                if ring_overflows != 0u {
                    why |= STOPPED_RINGS;
                }
                if atomicLoad(&status.longest) > bitcast<u32>(params.assumed_move) {
                    why |= STOPPED_MOVE;
                }
                if atomicLoad(&status.edge) > bitcast<u32>(params.max_edge) {
                    why |= STOPPED_EDGES;
                }
                status.stopped = why;
            }
        }
        default: {
            if i < params.capacity && status.stopped != 0u {
                moving[i].vertex = INVALID;
            }
        }
    }
}
