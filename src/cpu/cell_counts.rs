//! Mirror of `wgsl/cell_counts.wgsl`. Run in order, the atomics hand out ranks in vertex order,
//! so the CPU table lists each bucket's vertices ascending; the GPU's order within a bucket is
//! arbitrary and only the bucket's set is comparable.

use super::shared::invocations;
use crate::abi::CountParams;
use crate::mesh::{INVALID, VertexFlags};

/// `counts[keys[i]] += 1` for every live vertex `i`, and `ranks[i]` = its count before that.
pub fn cell_counts(
    params: &CountParams,
    keys: &[u32],
    flags: &[u32],
    counts: &mut [u32],
    ranks: &mut [u32],
) {
    for i in invocations(params.count) {
        let i = i as usize;
        if flags[i] & VertexFlags::DEAD.bits() != 0 {
            ranks[i] = INVALID;
            continue;
        }
        let count = &mut counts[keys[i] as usize];
        ranks[i] = *count;
        *count += 1;
    }
}
