//! The spatial hash on the GPU (docs/design.md, "Data"): a counting sort of vertex ids by bucket into a CSR
//! table, rebuilt from scratch by four kernels — `cell_keys` → `cell_counts` → exclusive scan
//! (`scan`, `scan_add`) → `scatter`.
//!
//! Layout: `offsets` has `table_size + 1` entries and bucket `b` holds
//! `entries[offsets[b]..offsets[b + 1]]`; the extra count slot is never incremented, so the scan
//! turns it into the number of filed vertices. Buckets are the grid's [`crate::grid::hash_cell`]
//! slots, so a cell's vertices are those of its bucket whose position lies in the cell (cells
//! sharing a bucket share its slice, exactly as in [`crate::grid::SpatialHash`]). Dead vertices
//! are not filed. The order within a bucket depends on the order the counting atomics ran in:
//! compare buckets as sets.

use glam::Vec3;

use super::scan::record_exclusive_scan;
use super::{GpuContext, GpuError, record_cell_keys};
use crate::abi::{CountParams, CsrTable, WORKGROUP_SIZE};

/// Buckets for `vertices` vertices, as [`crate::grid::SpatialHash`] sizes its table: a power
/// of two, at least twice the count and at least 1024.
pub fn table_size_for(vertices: usize) -> u32 {
    (2 * vertices).next_power_of_two().max(1024) as u32
}

/// A hash table in GPU memory. Kernels that query it bind `offsets` and `entries` and filter
/// a bucket's vertices by cell.
pub struct GpuHashTable {
    pub table_size: u32,
    pub inv_cell_size: f32,
    pub vertex_count: usize,
    /// Per vertex: its bucket.
    pub keys: wgpu::Buffer,
    /// `table_size + 1` bucket starts.
    pub offsets: wgpu::Buffer,
    /// `vertex_count` slots; the first `offsets[table_size]` are filled.
    pub entries: wgpu::Buffer,
}

impl GpuHashTable {
    /// Records the build of a table over `vertex_count` packed positions and their
    /// [`crate::mesh::VertexFlags`] bits (dead vertices are left out).
    pub fn record(
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        positions: &wgpu::Buffer,
        flags: &wgpu::Buffer,
        vertex_count: usize,
        inv_cell_size: f32,
        table_size: u32,
    ) -> Result<GpuHashTable, GpuError> {
        if !table_size.is_power_of_two() || table_size == u32::MAX {
            return Err(GpuError::Validation(format!(
                "hash table size {table_size} is not a power of two"
            )));
        }
        gpu.check_binding::<Vec3>("vertex positions", vertex_count)?;
        gpu.check_binding::<u32>("hash table offsets", table_size as usize + 1)?;
        let keys = gpu.output_buffer::<u32>("hash keys", vertex_count);
        let ranks = gpu.output_buffer::<u32>("hash ranks", vertex_count);
        // Zeroed at creation: the counts start from nothing.
        let offsets = gpu.output_buffer::<u32>("hash offsets", table_size as usize + 1);
        let entries = gpu.output_buffer::<u32>("hash entries", vertex_count);
        record_cell_keys(
            gpu,
            encoder,
            positions,
            &keys,
            vertex_count,
            inv_cell_size,
            table_size,
        )?;
        record_counting_sort(
            gpu,
            encoder,
            (&keys, flags, &ranks),
            (&offsets, &entries),
            vertex_count,
            table_size,
        )?;
        Ok(GpuHashTable {
            table_size,
            inv_cell_size,
            vertex_count,
            keys,
            offsets,
            entries,
        })
    }

    /// Copies the table back.
    pub fn read(&self, gpu: &GpuContext) -> Result<CsrTable, GpuError> {
        read_table(gpu, (&self.offsets, &self.entries), self.table_size)
    }
}

/// Copies back a table of `table_size` buckets from its `offsets` and `entries` buffers (the
/// main table's or the overlay's): the offsets, then as many entries as they say are filed.
pub fn read_table(
    gpu: &GpuContext,
    (offsets, entries): (&wgpu::Buffer, &wgpu::Buffer),
    table_size: u32,
) -> Result<CsrTable, GpuError> {
    let offsets: Vec<u32> = gpu.read_buffer(offsets, table_size as usize + 1)?;
    let filed = offsets[table_size as usize] as usize;
    let entries = gpu.read_buffer(entries, filed)?;
    Ok(CsrTable { offsets, entries })
}

/// Records the counting sort of `count` items by their `keys` (those whose `flags` say dead left
/// out; `ranks` is scratch of `count` words) into a table of `table_size` buckets: `offsets`,
/// zero on entry, becomes the bucket starts and `entries` the item indices, bucket by bucket.
pub fn record_counting_sort(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (keys, flags, ranks): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
    (offsets, entries): (&wgpu::Buffer, &wgpu::Buffer),
    count: usize,
    table_size: u32,
) -> Result<(), GpuError> {
    let per_item = gpu.uniform_buffer("hash params", &CountParams::new(count));
    let cell_counts = gpu.compute_pipeline("cell_counts")?;
    gpu.record_dispatch(
        encoder,
        &cell_counts,
        "cell_counts",
        &[&per_item, keys, flags, offsets, ranks],
        count,
        WORKGROUP_SIZE,
    );
    record_exclusive_scan(gpu, encoder, offsets, table_size as usize + 1)?;
    let scatter = gpu.compute_pipeline("scatter")?;
    gpu.record_dispatch(
        encoder,
        &scatter,
        "scatter",
        &[&per_item, keys, ranks, offsets, entries],
        count,
        WORKGROUP_SIZE,
    );
    Ok(())
}

/// Builds the table for `positions` and per-vertex flag bits on the GPU and reads it back.
pub fn run_hash_table(
    gpu: &GpuContext,
    positions: &[Vec3],
    flags: &[u32],
    inv_cell_size: f32,
    table_size: u32,
) -> Result<CsrTable, GpuError> {
    assert_eq!(positions.len(), flags.len(), "one flag word per vertex");
    gpu.check_binding::<Vec3>("vertex positions", positions.len())?;
    let positions_buffer = gpu.storage_buffer("positions", positions, false);
    let flags_buffer = gpu.storage_buffer("flags", flags, false);
    let mut encoder = gpu.encoder("hash table");
    let table = GpuHashTable::record(
        gpu,
        &mut encoder,
        &positions_buffer,
        &flags_buffer,
        positions.len(),
        inv_cell_size,
        table_size,
    )?;
    gpu.submit(encoder);
    table.read(gpu)
}

/// `cell_counts` alone: bucket counts (`table_size + 1` of them) and per-vertex ranks.
pub fn run_cell_counts(
    gpu: &GpuContext,
    keys: &[u32],
    flags: &[u32],
    table_size: u32,
) -> Result<(Vec<u32>, Vec<u32>), GpuError> {
    let keys_buffer = gpu.storage_buffer("keys", keys, false);
    let flags_buffer = gpu.storage_buffer("flags", flags, false);
    let counts = gpu.output_buffer::<u32>("counts", table_size as usize + 1);
    let ranks = gpu.output_buffer::<u32>("ranks", keys.len());
    let params = gpu.uniform_buffer("cell_counts params", &CountParams::new(keys.len()));
    let pipeline = gpu.compute_pipeline("cell_counts")?;
    let mut encoder = gpu.encoder("cell_counts");
    gpu.record_dispatch(
        &mut encoder,
        &pipeline,
        "cell_counts",
        &[&params, &keys_buffer, &flags_buffer, &counts, &ranks],
        keys.len(),
        WORKGROUP_SIZE,
    );
    gpu.submit(encoder);
    Ok((
        gpu.read_buffer(&counts, table_size as usize + 1)?,
        gpu.read_buffer(&ranks, keys.len())?,
    ))
}

/// `scatter` alone, given keys, ranks and scanned offsets.
pub fn run_scatter(
    gpu: &GpuContext,
    keys: &[u32],
    ranks: &[u32],
    offsets: &[u32],
) -> Result<Vec<u32>, GpuError> {
    let filed = offsets.last().copied().unwrap_or(0) as usize;
    let buffers = [
        gpu.storage_buffer("keys", keys, false),
        gpu.storage_buffer("ranks", ranks, false),
        gpu.storage_buffer("offsets", offsets, false),
    ];
    let entries = gpu.output_buffer::<u32>("entries", keys.len());
    let params = gpu.uniform_buffer("scatter params", &CountParams::new(keys.len()));
    let pipeline = gpu.compute_pipeline("scatter")?;
    let mut encoder = gpu.encoder("scatter");
    gpu.record_dispatch(
        &mut encoder,
        &pipeline,
        "scatter",
        &[&params, &buffers[0], &buffers[1], &buffers[2], &entries],
        keys.len(),
        WORKGROUP_SIZE,
    );
    gpu.submit(encoder);
    gpu.read_buffer(&entries, filed)
}
