//! Host side of `wgsl/brush_frame.wgsl`: the brush frame's fixed-point sums over a selection
//! list on the GPU, so that `deform` can take the dab's normal and plane point in the same
//! submission as the selection (see `GpuKernels::select_and_deform`).

use glam::Vec3;

use super::{GpuContext, GpuError, SelectionBuffers, Workgroups};
use crate::abi::{
    FRAME_SUM_WORDS, FRAME_WORKGROUP_SIZE, FrameParams, FrameSums, SelectedVertex, frame_params,
};

/// The buffer of the sums: `FRAME_SUM_WORDS` words, `COPY_SRC` for the read-back.
pub fn frame_sums_buffer(gpu: &GpuContext) -> wgpu::Buffer {
    gpu.output_buffer::<u32>("brush frame sums", FRAME_SUM_WORDS)
}

/// Records the sums of the selection into `sums` (cleared first); `workgroups` covers the
/// selection (an indirect dispatch sized from its count, when only the GPU knows it).
pub fn record_brush_frame(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    inputs: &SelectionBuffers<'_>,
    params: &FrameParams,
    sums: &wgpu::Buffer,
    workgroups: Workgroups<'_>,
) -> Result<(), GpuError> {
    let pipeline = gpu.compute_pipeline("brush_frame")?;
    let uniform = gpu.uniform_buffer("brush_frame params", params);
    encoder.clear_buffer(sums, 0, None);
    gpu.record_paged_dispatch(
        encoder,
        &pipeline,
        "brush_frame",
        &[
            &uniform,
            inputs.positions,
            inputs.normals,
            inputs.selected,
            inputs.selection_count,
            sums,
        ],
        &[],
        workgroups,
    );
    Ok(())
}

/// The sums of `selection` about `center` (brush `radius`) on the GPU, dispatched indirectly
/// from the count as `GpuKernels` dispatches them.
pub fn run_brush_frame(
    gpu: &GpuContext,
    (positions, normals): (&[Vec3], &[Vec3]),
    selection: &[SelectedVertex],
    center: Vec3,
    radius: f32,
) -> Result<FrameSums, GpuError> {
    let positions = gpu.storage_buffer("positions", positions, false);
    let normals = gpu.storage_buffer("normals", normals, false);
    let selected = gpu.storage_buffer("selected", selection, false);
    let count = gpu.storage_buffer("selection count", &[selection.len() as u32], false);
    let args = super::indirect_args_buffer(gpu, "brush_frame sizes");
    let sums = frame_sums_buffer(gpu);
    let mut encoder = gpu.encoder("brush_frame");
    super::record_dispatch_args(
        gpu,
        &mut encoder,
        &count,
        (selection.len(), 1),
        FRAME_WORKGROUP_SIZE,
        &args,
    )?;
    record_brush_frame(
        gpu,
        &mut encoder,
        &SelectionBuffers {
            positions: &positions,
            normals: &normals,
            selected: &selected,
            selection_count: &count,
        },
        &frame_params(center, radius, selection.len()),
        &sums,
        Workgroups::Indirect(&args),
    )?;
    gpu.submit(encoder);
    let words = gpu.read_buffer::<u32>(&sums, FRAME_SUM_WORDS)?;
    Ok(words.try_into().expect("the sums' words"))
}
