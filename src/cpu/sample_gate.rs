//! Mirror of `wgsl/sample_gate.wgsl`: the gate of a run of samples recorded ahead, one stage
//! per call as the host records them.

use super::shared::invocations;
use crate::abi::{GateParams, GateStage, GateStatus, MovingVertex};
use crate::mesh::INVALID;

/// The buffers `sample_gate` writes.
pub struct GateState<'a> {
    pub selection_count: &'a mut u32,
    pub moving: &'a mut [MovingVertex],
    pub status: &'a mut GateStatus,
}

/// Runs the stage `params.stage` names: [`GateStage::Open`] resets the longest move (and at an
/// ordinary call the deferral) and empties the selection of a stopped run or of a step whose
/// sample did not defer; [`GateStage::Decide`] records why the sample stops the run (nothing
/// when it holds) and, at a start that may defer, whether it did; [`GateStage::Vacate`]
/// vacates the first `params.capacity` moving entries where the call moves nothing.
/// `ring_overflows` counts the rings `moving_entries` cut.
pub fn sample_gate(params: &GateParams, ring_overflows: u32, gate: GateState<'_>) {
    let GateState {
        selection_count,
        moving,
        status,
    } = gate;
    if params.stage == GateStage::Open as u32 {
        for _ in invocations(1) {
            status.longest = 0;
            if params.if_deferred == 0 {
                status.deferred = 0;
            }
            if status.stopped != 0 || status.deferred != params.if_deferred {
                *selection_count = 0;
            }
        }
    } else if params.stage == GateStage::Decide as u32 {
        for _ in invocations(1) {
            let mut why = 0;
            if status.stopped != 0 {
                why |= GateStatus::EARLIER;
            }
            if *selection_count > params.capacity {
                why |= GateStatus::SELECTION;
            }
            if ring_overflows != 0 {
                why |= GateStatus::RINGS;
            }
            // Over the step limit by at most twice, where the sample's two steps follow.
            let defers = params.defer_over > 0.0
                && status.longest > params.defer_over.to_bits()
                && status.longest <= (2.0 * params.defer_over).to_bits();
            if status.longest > params.assumed_move.to_bits() && !defers {
                why |= GateStatus::MOVE;
            }
            if status.edge > params.max_edge.to_bits() {
                why |= GateStatus::EDGES;
            }
            status.stopped = why;
            if params.defer_over > 0.0 {
                status.deferred = u32::from(defers && why == 0);
            }
        }
    } else {
        // A start that deferred moves nothing, nor does a step whose sample did not.
        let idle = status.stopped != 0 || status.deferred != params.if_deferred;
        for i in invocations(params.capacity) {
            if idle {
                moving[i as usize].vertex = INVALID;
            }
        }
    }
}
