//! The hash-table build chained from the kernel mirrors, step for step as
//! `src/gpu/hash_table.rs` and `src/gpu/scan.rs` record it on the GPU: the reference the GPU
//! table is compared with.

use glam::Vec3;

use super::{cell_counts, cell_keys, scan, scan_add, scatter};
use crate::gpu::{CellKeyParams, CountParams, CsrTable, SCAN_BLOCK};

/// Exclusive prefix sum in place, by the same levels of blocks as `record_exclusive_scan`.
pub fn exclusive_scan(values: &mut [u32]) {
    if values.is_empty() {
        return;
    }
    let params = CountParams::new(values.len());
    let mut sums = vec![0u32; values.len().div_ceil(SCAN_BLOCK as usize)];
    scan(&params, values, &mut sums);
    if values.len() > SCAN_BLOCK as usize {
        exclusive_scan(&mut sums);
        scan_add(&params, values, &sums);
    }
}

/// The CSR table of `positions` (dead vertices, per `flags`, left out).
pub fn hash_table(
    positions: &[Vec3],
    flags: &[u32],
    inv_cell_size: f32,
    table_size: u32,
) -> CsrTable {
    let count = positions.len();
    let key_params = CellKeyParams {
        count: count as u32,
        table_mask: table_size - 1,
        inv_cell_size,
        _pad: 0,
    };
    let flat: &[f32] = bytemuck::cast_slice(positions);
    let mut keys = vec![0u32; count];
    cell_keys(&key_params, flat, &mut keys);
    let params = CountParams::new(count);
    let mut offsets = vec![0u32; table_size as usize + 1];
    let mut ranks = vec![0u32; count];
    cell_counts(&params, &keys, flags, &mut offsets, &mut ranks);
    exclusive_scan(&mut offsets);
    let mut entries = vec![0u32; offsets[table_size as usize] as usize];
    scatter(&params, &keys, &ranks, &offsets, &mut entries);
    CsrTable { offsets, entries }
}
