//! The hash-table build chained from the kernel mirrors, step for step as
//! `src/gpu/hash_table.rs` and `src/gpu/scan.rs` record it on the GPU: the reference the GPU
//! table is compared with.

use glam::Vec3;

use super::{
    OverlaySlots, cell_counts, cell_keys, overlay_entries, overlay_keys, scan, scan_add, scatter,
};
use crate::abi::{CellKeyParams, CountParams, CsrTable, OverlayParams, SCAN_BLOCK};

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

/// The overlay table of `slots` (`params.room` of them; `table_mask`, `inv_cell_size` its
/// table's), as `src/gpu/overlay.rs` rebuilds it on the GPU: keys and flags per slot, the
/// counting sort over every slot of the room, slots turned into vertex ids.
pub fn overlay_slot_table(params: &OverlayParams, slots: &OverlaySlots) -> CsrTable {
    let room = params.room as usize;
    let over_slots = OverlayParams {
        count: params.room,
        ..*params
    };
    let mut keys = vec![0u32; room];
    let mut flags = vec![0u32; room];
    overlay_keys(
        &over_slots,
        &slots.members,
        slots.member_count,
        &slots.filed_at,
        &mut keys,
        &mut flags,
    );
    let count = CountParams::new(room);
    let table_size = params.table_mask as usize + 1;
    let mut offsets = vec![0u32; table_size + 1];
    let mut ranks = vec![0u32; room];
    cell_counts(&count, &keys, &flags, &mut offsets, &mut ranks);
    exclusive_scan(&mut offsets);
    let mut entries = vec![0u32; offsets[table_size] as usize];
    scatter(&count, &keys, &ranks, &offsets, &mut entries);
    overlay_entries(&over_slots, &slots.members, &offsets, &mut entries);
    CsrTable { offsets, entries }
}
