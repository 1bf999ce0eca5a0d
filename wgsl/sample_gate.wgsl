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
                if params.if_deferred == 0u {
                    status.deferred = 0u;
                }
                if status.stopped != 0u || status.deferred != params.if_deferred {
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
                let longest = atomicLoad(&status.longest);
                // Over the step limit by at most twice, where the sample's two steps follow.
                let defers = params.defer_over > 0.0
                    && longest > bitcast<u32>(params.defer_over)
                    && longest <= bitcast<u32>(2.0 * params.defer_over);
                if longest > bitcast<u32>(params.assumed_move) && !defers {
                    why |= STOPPED_MOVE;
                }
                if atomicLoad(&status.edge) > bitcast<u32>(params.max_edge) {
                    why |= STOPPED_EDGES;
                }
                status.stopped = why;
                if params.defer_over > 0.0 {
                    status.deferred = select(0u, 1u, defers && why == 0u);
                }
            }
        }
        default: {
            // A start that deferred moves nothing, nor does a step whose sample did not.
            let idle = status.stopped != 0u || status.deferred != params.if_deferred;
            if i < params.capacity && idle {
                moving[i].vertex = INVALID;
            }
        }
    }
}
