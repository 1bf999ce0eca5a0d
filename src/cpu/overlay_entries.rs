//! Mirror of `wgsl/overlay_entries.wgsl`.

use super::shared::invocations;
use crate::abi::OverlayParams;

/// Each filed entry (the first `offsets[table_mask + 1]`, within `params.count`) turned from
/// a slot into that slot's member.
pub fn overlay_entries(
    params: &OverlayParams,
    members: &[u32],
    offsets: &[u32],
    entries: &mut [u32],
) {
    let filed = offsets[params.table_mask as usize + 1];
    for j in invocations(params.count) {
        if j >= filed {
            continue;
        }
        let e = &mut entries[j as usize];
        *e = members[*e as usize];
    }
}
