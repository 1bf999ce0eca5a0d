//! Mirror of `wgsl/overlay_members.wgsl`: a step's moved vertices filed in the overlay's slots
//! where they now are.

use super::shared::{invocations, packed_position};
use crate::abi::{MovingVertex, OverlayParams};
use crate::mesh::INVALID;

/// The overlay's slots as `overlay_members` and `overlay_keys` read and write them.
#[derive(Debug, Clone, PartialEq)]
pub struct OverlaySlots {
    /// Per vertex: its slot + 1 when the overlay holds it, else 0.
    pub marks: Vec<u32>,
    /// `room` slots; the first `member_count` hold vertex ids.
    pub members: Vec<u32>,
    /// Slots taken (may pass `room` when the host sized it too small; those past are unfiled).
    pub member_count: u32,
    /// Per vertex, packed x, y, z: where it is filed.
    pub filed_at: Vec<f32>,
}

/// Over the first `params.count` slots of `moving`: each entry whose vertex is away from its
/// start in `positions` (packed x, y, z) is filed at its position, taking the next slot when the
/// overlay does not hold it yet. The GPU hands slots out in the order its atomics run; here in
/// invocation order.
pub fn overlay_members(
    params: &OverlayParams,
    positions: &[f32],
    moving: &[MovingVertex],
    slots: &mut OverlaySlots,
) {
    for i in invocations(params.count) {
        let entry = &moving[i as usize];
        if entry.vertex == INVALID {
            continue;
        }
        let v = entry.vertex as usize;
        let p = packed_position(positions, entry.vertex);
        if p.to_array() == entry.start {
            continue;
        }
        if slots.marks[v] == 0 {
            let slot = slots.member_count;
            slots.member_count += 1;
            if slot >= params.room {
                continue;
            }
            slots.members[slot as usize] = entry.vertex;
            slots.marks[v] = slot + 1;
        }
        slots.filed_at[3 * v..3 * v + 3].copy_from_slice(&p.to_array());
    }
}
