//! Mirror of `wgsl/longest_move.wgsl`: a sample's longest move, as f32 bits in the gate status.

use super::shared::{invocations, packed_position};
use crate::abi::{GateParams, GateStatus, SelectedVertex};

/// Over the first `min(selection_count, params.capacity)` entries of `selected`: the largest
/// distance from the vertex's position in `positions` to its target in `targets` (both packed
/// x, y, z) folded into `status.longest` as bits, which order as the non-negative floats do
/// (NaN above every finite distance).
pub fn longest_move(
    params: &GateParams,
    (positions, targets): (&[f32], &[f32]),
    (selected, selection_count): (&[SelectedVertex], u32),
    status: &mut GateStatus,
) {
    for i in invocations(selection_count.min(params.capacity)) {
        let p = packed_position(positions, selected[i as usize].vertex);
        let q = packed_position(targets, i);
        status.longest = status.longest.max(p.distance(q).to_bits());
    }
}
