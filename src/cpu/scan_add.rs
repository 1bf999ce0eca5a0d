//! Mirror of `wgsl/scan_add.wgsl`.

use crate::abi::{CountParams, SCAN_BLOCK};

/// Adds `block_offsets[b]` to every value of block `b`.
pub fn scan_add(params: &CountParams, values: &mut [u32], block_offsets: &[u32]) {
    let blocks = params.count.div_ceil(SCAN_BLOCK);
    for block in 0..blocks {
        for local in 0..SCAN_BLOCK {
            let i = block * SCAN_BLOCK + local;
            if i < params.count {
                let v = &mut values[i as usize];
                *v = v.wrapping_add(block_offsets[block as usize]);
            }
        }
    }
}
