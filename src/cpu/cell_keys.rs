//! Mirror of `wgsl/cell_keys.wgsl`.

use glam::Vec3;

use crate::gpu::CellKeyParams;
use crate::grid::{cell_coordinates, hash_cell};

const WORKGROUP_SIZE: u32 = 64;

/// `keys[i]` = hash-table slot of the cell of `positions[i]`.
pub fn cell_keys(params: &CellKeyParams, positions: &[f32], keys: &mut [u32]) {
    let workgroups = params.count.div_ceil(WORKGROUP_SIZE);
    for workgroup in 0..workgroups {
        for local in 0..WORKGROUP_SIZE {
            let i = workgroup * WORKGROUP_SIZE + local;
            if i >= params.count {
                continue;
            }
            let i = i as usize;
            let p = Vec3::new(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
            keys[i] = hash_cell(
                cell_coordinates(p, params.inv_cell_size),
                params.table_mask + 1,
            );
        }
    }
}
