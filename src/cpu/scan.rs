//! Mirror of `wgsl/scan.wgsl`: per block of `SCAN_BLOCK` values, an exclusive prefix sum in
//! place and the block's total in `block_sums`, by the same Hillis–Steele rounds.

use crate::abi::{CountParams, SCAN_BLOCK};

pub fn scan(params: &CountParams, values: &mut [u32], block_sums: &mut [u32]) {
    let block_size = SCAN_BLOCK as usize;
    let blocks = params.count.div_ceil(SCAN_BLOCK);
    let mut running = vec![0u32; block_size];
    let mut left = vec![0u32; block_size];
    for block in 0..blocks {
        let base = (block * SCAN_BLOCK) as usize;
        let within = |local: usize| base + local < params.count as usize;
        for (local, slot) in running.iter_mut().enumerate() {
            *slot = if within(local) {
                values[base + local]
            } else {
                0
            };
        }
        let mut offset = 1;
        while offset < block_size {
            // Between the shader's two barriers every invocation reads, then every one adds.
            for local in 0..block_size {
                left[local] = if local >= offset {
                    running[local - offset]
                } else {
                    0
                };
            }
            for local in 0..block_size {
                running[local] = running[local].wrapping_add(left[local]);
            }
            offset <<= 1;
        }
        for local in 0..block_size {
            if within(local) {
                values[base + local] = running[local].wrapping_sub(values[base + local]);
            }
        }
        block_sums[block as usize] = running[block_size - 1];
    }
}
