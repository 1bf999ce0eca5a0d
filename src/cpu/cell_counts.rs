//! Mirror of `wgsl/cell_counts.wgsl`. Run in order, the atomics hand out ranks in vertex order,
//! so the CPU table lists each bucket's vertices ascending; the GPU's order within a bucket is
//! arbitrary and only the bucket's set is comparable.

use crate::gpu::CountParams;
use crate::mesh::{INVALID, VertexFlags};

const WORKGROUP_SIZE: u32 = 64;

/// `counts[keys[i]] += 1` for every live vertex `i`, and `ranks[i]` = its count before that.
pub fn cell_counts(
    params: &CountParams,
    keys: &[u32],
    flags: &[u32],
    counts: &mut [u32],
    ranks: &mut [u32],
) {
    let workgroups = params.count.div_ceil(WORKGROUP_SIZE);
    for workgroup in 0..workgroups {
        for local in 0..WORKGROUP_SIZE {
            let i = workgroup * WORKGROUP_SIZE + local;
            if i >= params.count {
                continue;
            }
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
}
