//! Host side of `wgsl/apply_moves.wgsl`: the writes that chain proximity passes into a whole
//! Jacobi loop on the GPU.

use glam::Vec3;

use super::{GpuContext, GpuError};
use crate::abi::{APPLY_WORKGROUP_SIZE, ApplyMode, ApplyParams, MovingVertex};

/// What `apply_moves` binds besides its parameters.
pub struct ApplyMovesBuffers<'a> {
    pub moving: &'a wgpu::Buffer,
    pub targets: &'a wgpu::Buffer,
    /// Per entry: the proximity pass's pull-back amount (zeroed as consumed).
    pub pulls: &'a wgpu::Buffer,
    pub positions: &'a wgpu::Buffer,
    pub marks: &'a wgpu::Buffer,
    pub next_count: &'a wgpu::Buffer,
    pub finals: &'a wgpu::Buffer,
}

/// Records one `apply_moves` pass over `params.count` entries, sized on the host, or by the
/// GPU from `indirect` (three workgroup counts) when given.
pub fn record_apply_moves(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    buffers: &ApplyMovesBuffers<'_>,
    params: &ApplyParams,
    indirect: Option<&wgpu::Buffer>,
) -> Result<(), GpuError> {
    let pipeline = gpu.compute_pipeline("apply_moves")?;
    let uniform = gpu.uniform_buffer("apply_moves params", params);
    let resources = [
        &uniform,
        buffers.moving,
        buffers.targets,
        buffers.pulls,
        buffers.positions,
        buffers.marks,
        buffers.next_count,
        buffers.finals,
    ];
    match indirect {
        Some(args) => {
            gpu.record_dispatch_indirect(encoder, &pipeline, "apply_moves", &resources, args)
        }
        None => gpu.record_dispatch(
            encoder,
            &pipeline,
            "apply_moves",
            &resources,
            params.count as usize,
            APPLY_WORKGROUP_SIZE,
        ),
    }
    Ok(())
}

/// What one pass left: positions, marks, amounts, the next pass's count, and the finals.
#[derive(Debug, Clone, PartialEq)]
pub struct AppliedMoves {
    pub positions: Vec<Vec3>,
    pub marks: Vec<u32>,
    pub pulls: Vec<u32>,
    pub next_count: u32,
    pub finals: Vec<Vec3>,
}

/// Runs one pass of `mode` on the GPU over buffers holding the given data.
pub fn run_apply_moves(
    gpu: &GpuContext,
    mode: ApplyMode,
    moving: &[MovingVertex],
    targets: &[Vec3],
    pulls: &[u32],
    positions: &[Vec3],
    marks: &[u32],
) -> Result<AppliedMoves, GpuError> {
    let buffers = [
        gpu.storage_buffer("moving", moving, false),
        gpu.storage_buffer("targets", targets, false),
        gpu.storage_buffer("pulls", pulls, true),
        gpu.storage_buffer("positions", positions, true),
        gpu.storage_buffer("marks", marks, true),
        gpu.output_buffer::<u32>("next count", 1),
        gpu.output_buffer::<Vec3>("finals", moving.len()),
    ];
    let mut encoder = gpu.encoder("apply_moves");
    record_apply_moves(
        gpu,
        &mut encoder,
        &ApplyMovesBuffers {
            moving: &buffers[0],
            targets: &buffers[1],
            pulls: &buffers[2],
            positions: &buffers[3],
            marks: &buffers[4],
            next_count: &buffers[5],
            finals: &buffers[6],
        },
        &ApplyParams::new(moving.len(), mode),
        None,
    )?;
    gpu.submit(encoder);
    Ok(AppliedMoves {
        positions: gpu.read_buffer(&buffers[3], positions.len())?,
        marks: gpu.read_buffer(&buffers[4], marks.len())?,
        pulls: gpu.read_buffer(&buffers[2], pulls.len())?,
        next_count: gpu.read_buffer::<u32>(&buffers[5], 1)?[0],
        finals: gpu.read_buffer(&buffers[6], moving.len())?,
    })
}
