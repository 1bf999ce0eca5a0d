//! Host side of `wgsl/cell_keys.wgsl`.

use glam::Vec3;

use super::{GpuContext, GpuError};
use crate::abi::{CellKeyParams, WORKGROUP_SIZE};

/// Records the pass writing `keys[i]`, the hash-table slot of the cell of vertex `i`, for the
/// first `count` packed positions.
pub fn record_cell_keys(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    positions: &wgpu::Buffer,
    keys: &wgpu::Buffer,
    count: usize,
    inv_cell_size: f32,
    table_size: u32,
) -> Result<(), GpuError> {
    debug_assert!(table_size.is_power_of_two());
    let params = CellKeyParams {
        count: count as u32,
        table_mask: table_size - 1,
        inv_cell_size,
        _pad: 0,
    };
    let pipeline = gpu.compute_pipeline("cell_keys")?;
    let uniform = gpu.uniform_buffer("cell_keys params", &params);
    gpu.record_dispatch(
        encoder,
        &pipeline,
        "cell_keys",
        &[&uniform, positions, keys],
        count,
        WORKGROUP_SIZE,
    );
    Ok(())
}

/// Hash-table slots of every position's cell, computed on the GPU.
pub fn run_cell_keys(
    gpu: &GpuContext,
    positions: &[Vec3],
    inv_cell_size: f32,
    table_size: u32,
) -> Result<Vec<u32>, GpuError> {
    gpu.check_binding::<Vec3>("positions", positions.len())?;
    let input = gpu.storage_buffer("positions", positions, false);
    let keys = gpu.output_buffer::<u32>("keys", positions.len());
    let mut encoder = gpu.encoder("cell_keys");
    record_cell_keys(
        gpu,
        &mut encoder,
        &input,
        &keys,
        positions.len(),
        inv_cell_size,
        table_size,
    )?;
    gpu.submit(encoder);
    gpu.read_buffer(&keys, positions.len())
}
