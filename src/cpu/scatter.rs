//! Mirror of `wgsl/scatter.wgsl`.

use super::shared::invocations;
use crate::abi::CountParams;
use crate::mesh::INVALID;

/// `entries[offsets[keys[i]] + ranks[i]] = i` for every vertex with a rank.
pub fn scatter(
    params: &CountParams,
    keys: &[u32],
    ranks: &[u32],
    offsets: &[u32],
    entries: &mut [u32],
) {
    for i in invocations(params.count) {
        let rank = ranks[i as usize];
        if rank == INVALID {
            continue;
        }
        entries[(offsets[keys[i as usize] as usize] + rank) as usize] = i;
    }
}
