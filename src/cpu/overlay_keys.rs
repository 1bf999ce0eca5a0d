//! Mirror of `wgsl/overlay_keys.wgsl`.

use super::shared::{invocations, packed_position};
use crate::abi::OverlayParams;
use crate::grid::{cell_coordinates, hash_cell};
use crate::mesh::VertexFlags;

/// Over the first `params.count` slots: a member's bucket from where it is filed and a live
/// flag word; past the member count (or the room), a dead flag word.
pub fn overlay_keys(
    params: &OverlayParams,
    members: &[u32],
    member_count: u32,
    filed_at: &[f32],
    keys: &mut [u32],
    flags: &mut [u32],
) {
    for slot in invocations(params.count) {
        let s = slot as usize;
        if slot >= member_count.min(params.room) {
            flags[s] = VertexFlags::DEAD.bits();
            continue;
        }
        let p = packed_position(filed_at, members[s]);
        keys[s] = hash_cell(
            cell_coordinates(p, params.inv_cell_size),
            params.table_mask + 1,
        );
        flags[s] = 0;
    }
}
