//! Host side of `wgsl/cell_keys.wgsl`.

use glam::Vec3;

use super::{CellKeyParams, GpuContext, GpuError};

/// Workgroup size declared in the shader.
const WORKGROUP_SIZE: u32 = 64;

/// Hash-table slots of every position's cell, computed on the GPU.
pub fn run_cell_keys(
    gpu: &GpuContext,
    positions: &[Vec3],
    inv_cell_size: f32,
    table_size: u32,
) -> Result<Vec<u32>, GpuError> {
    let params = CellKeyParams {
        count: positions.len() as u32,
        table_mask: table_size - 1,
        inv_cell_size,
        _pad: 0,
    };
    let pipeline = gpu.compute_pipeline("cell_keys")?;
    let uniform = gpu.uniform_buffer("cell_keys params", &params);
    let input = gpu.storage_buffer("positions", positions, false);
    let keys = gpu.output_buffer::<u32>("keys", positions.len());
    let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("cell_keys"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: input.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: keys.as_entire_binding(),
            },
        ],
    });
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("cell_keys"),
        });
    if !positions.is_empty() {
        let (x, y) = gpu.dispatch_size(positions.len(), WORKGROUP_SIZE);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("cell_keys"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
    gpu.queue.submit([encoder.finish()]);
    gpu.read_buffer(&keys, positions.len())
}
