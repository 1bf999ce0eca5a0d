//! Mirror of `wgsl/cell_keys.wgsl`.

use super::shared::{invocations, packed_position};
use crate::abi::CellKeyParams;
use crate::grid::{cell_coordinates, hash_cell};

/// `keys[i]` = hash-table slot of the cell of `positions[i]`.
pub fn cell_keys(params: &CellKeyParams, positions: &[f32], keys: &mut [u32]) {
    for i in invocations(params.count) {
        let p = packed_position(positions, i);
        keys[i as usize] = hash_cell(
            cell_coordinates(p, params.inv_cell_size),
            params.table_mask + 1,
        );
    }
}
