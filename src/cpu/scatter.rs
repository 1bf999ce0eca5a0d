//! Mirror of `wgsl/scatter.wgsl`.

use crate::gpu::CountParams;
use crate::mesh::INVALID;

const WORKGROUP_SIZE: u32 = 64;

/// `entries[offsets[keys[i]] + ranks[i]] = i` for every vertex with a rank.
pub fn scatter(
    params: &CountParams,
    keys: &[u32],
    ranks: &[u32],
    offsets: &[u32],
    entries: &mut [u32],
) {
    let workgroups = params.count.div_ceil(WORKGROUP_SIZE);
    for workgroup in 0..workgroups {
        for local in 0..WORKGROUP_SIZE {
            let i = workgroup * WORKGROUP_SIZE + local;
            if i >= params.count {
                continue;
            }
            let rank = ranks[i as usize];
            if rank == INVALID {
                continue;
            }
            entries[(offsets[keys[i as usize] as usize] + rank) as usize] = i;
        }
    }
}
