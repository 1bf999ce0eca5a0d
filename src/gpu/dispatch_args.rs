//! Host side of `wgsl/dispatch_args.wgsl`: indirect dispatch arguments from a GPU-side count.

use super::{GpuContext, GpuError};
use crate::abi::DispatchParams;

/// A buffer of three `u32` workgroup counts usable by `dispatch_workgroups_indirect`.
pub fn indirect_args_buffer(gpu: &GpuContext, label: &str) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: 12,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::INDIRECT
            | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

/// Records the pass writing into `args` the workgroups a kernel of `workgroup_size` needs
/// for `min(count, capacity) · per_item` invocations, folded as [`GpuContext::dispatch_size`]
/// folds.
pub fn record_dispatch_args(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    count: &wgpu::Buffer,
    (capacity, per_item): (usize, u32),
    workgroup_size: u32,
    args: &wgpu::Buffer,
) -> Result<(), GpuError> {
    let params = DispatchParams {
        workgroup_size,
        max_per_dimension: gpu.limits.max_compute_workgroups_per_dimension,
        capacity: capacity as u32,
        per_item,
    };
    let pipeline = gpu.compute_pipeline("dispatch_args")?;
    let uniform = gpu.uniform_buffer("dispatch_args params", &params);
    gpu.record_dispatch(
        encoder,
        &pipeline,
        "dispatch_args",
        &[&uniform, count, args],
        1,
        1,
    );
    Ok(())
}

/// The arguments for `count` items of `per_item` invocations, computed on the GPU and read
/// back.
pub fn run_dispatch_args(
    gpu: &GpuContext,
    count: u32,
    (capacity, per_item): (usize, u32),
    workgroup_size: u32,
) -> Result<[u32; 3], GpuError> {
    let count = gpu.storage_buffer("count", &[count], false);
    let args = indirect_args_buffer(gpu, "dispatch args");
    let mut encoder = gpu.encoder("dispatch_args");
    record_dispatch_args(
        gpu,
        &mut encoder,
        &count,
        (capacity, per_item),
        workgroup_size,
        &args,
    )?;
    gpu.submit(encoder);
    let values = gpu.read_buffer::<u32>(&args, 3)?;
    Ok([values[0], values[1], values[2]])
}
