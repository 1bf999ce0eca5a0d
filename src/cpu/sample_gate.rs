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

/// Runs the stage `params.stage` names: [`GateStage::Open`] resets the longest move and
/// empties a stopped run's selection; [`GateStage::Decide`] records why the sample stops the
/// run (nothing when it holds); [`GateStage::Vacate`] vacates the first `params.capacity`
/// moving entries of a stopped run. `ring_overflows` counts the rings `moving_entries` cut.
pub fn sample_gate(params: &GateParams, ring_overflows: u32, gate: GateState<'_>) {
    let GateState {
        selection_count,
        moving,
        status,
    } = gate;
    if params.stage == GateStage::Open as u32 {
        for _ in invocations(1) {
            status.longest = 0;
            if status.stopped != 0 {
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
            if status.longest > params.assumed_move.to_bits() {
                why |= GateStatus::MOVE;
            }
            if status.edge > params.max_edge.to_bits() {
                why |= GateStatus::EDGES;
            }
            status.stopped = why;
        }
    } else {
        for i in invocations(params.capacity) {
            if status.stopped != 0 {
                moving[i as usize].vertex = INVALID;
            }
        }
    }
}
