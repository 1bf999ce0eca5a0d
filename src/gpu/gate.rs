//! Host side of `wgsl/longest_move.wgsl`, `wgsl/sample_gate.wgsl` and `wgsl/moved_edges.wgsl`:
//! the gate that stops a run of samples recorded ahead in one submission at the first sample
//! whose passes were recorded on assumptions that fail (`wgsl/shared/gate.wgsl`), before that
//! sample moves anything, and makes every later sample of the run select nothing.

use glam::Vec3;

use super::vertex_normals::MovedPass;
use super::{GpuContext, GpuError};
use crate::abi::{
    GATE_WORKGROUP_SIZE, GateParams, GateSplit, GateStage, GateStatus, MovingVertex, SelectedVertex,
};
use crate::mesh::Mesh;

/// What the gate reads and writes.
pub struct GateBuffers<'a> {
    /// Packed x, y, z per vertex: the sample's start positions.
    pub positions: &'a wgpu::Buffer,
    pub selected: &'a wgpu::Buffer,
    pub selection_count: &'a wgpu::Buffer,
    /// Packed x, y, z per selection entry (`deform`'s).
    pub targets: &'a wgpu::Buffer,
    /// One `u32`: the rings `moving_entries` cut short.
    pub ring_overflows: &'a wgpu::Buffer,
    pub moving: &'a wgpu::Buffer,
    /// One [`GateStatus`] for the whole run, zeroed at its start.
    pub status: &'a wgpu::Buffer,
}

/// Invocations a `sample_gate` stage runs: one to open or decide, one per slot to vacate.
fn stage_invocations(params: &GateParams) -> usize {
    if params.stage == GateStage::Vacate as u32 {
        params.capacity as usize
    } else {
        1
    }
}

fn record_stage(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    gate: &GateBuffers<'_>,
    params: &GateParams,
) -> Result<(), GpuError> {
    let pipeline = gpu.compute_pipeline("sample_gate")?;
    let uniform = gpu.uniform_buffer("sample_gate params", params);
    gpu.record_dispatch(
        encoder,
        &pipeline,
        "sample_gate",
        &[
            &uniform,
            gate.selection_count,
            gate.ring_overflows,
            gate.moving,
            gate.status,
        ],
        stage_invocations(params),
        GATE_WORKGROUP_SIZE,
    );
    Ok(())
}

/// Records the gate's opening, right after the call's `select`: the longest move reset, and
/// the selection emptied when an earlier sample stopped the run (or, at a step of a sample
/// that may defer, as `split` says, when it did not).
pub fn record_gate_open(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    gate: &GateBuffers<'_>,
    split: GateSplit,
) -> Result<(), GpuError> {
    let params = GateParams::new(0, GateStage::Open, (0.0, 0.0)).split(split);
    record_stage(gpu, encoder, gate, &params)
}

/// Records the sample's check, after its `moving_entries` and before anything is applied:
/// `longest_move` over the first `capacity` selection entries, the verdict against
/// `capacity` and the move and edge bounds the passes were sized for (a start's move deferred
/// to its steps where `split` says they follow), and the moving list's `capacity` slots vacated
/// where the call moves nothing.
pub fn record_gate_check(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    gate: &GateBuffers<'_>,
    (capacity, assumed_move, max_edge): (usize, f32, f32),
    split: GateSplit,
) -> Result<(), GpuError> {
    let bounds = (assumed_move, max_edge);
    let params = GateParams::new(capacity, GateStage::Decide, bounds).split(split);
    let pipeline = gpu.compute_pipeline("longest_move")?;
    let uniform = gpu.uniform_buffer("longest_move params", &params);
    gpu.record_dispatch(
        encoder,
        &pipeline,
        "longest_move",
        &[
            &uniform,
            gate.positions,
            gate.selected,
            gate.selection_count,
            gate.targets,
            gate.status,
        ],
        capacity,
        GATE_WORKGROUP_SIZE,
    );
    record_stage(gpu, encoder, gate, &params)?;
    record_gate_vacate(gpu, encoder, gate, capacity, split)
}

/// Records the vacating of the first `capacity` slots of `gate.moving` where the call (as
/// `split` stands to a sample that may defer) moves nothing: a step's moving list before
/// anything is applied, or the lists a sample's steps kept for its normals.
pub fn record_gate_vacate(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    gate: &GateBuffers<'_>,
    capacity: usize,
    split: GateSplit,
) -> Result<(), GpuError> {
    let params = GateParams::new(capacity, GateStage::Vacate, (0.0, 0.0)).split(split);
    record_stage(gpu, encoder, gate, &params)
}

/// `longest_move` on the GPU over the first `min(selection_count, capacity)` entries, folded
/// into `status` and read back.
pub fn run_longest_move(
    gpu: &GpuContext,
    (positions, targets): (&[Vec3], &[Vec3]),
    (selected, selection_count): (&[SelectedVertex], u32),
    capacity: usize,
    status: GateStatus,
) -> Result<GateStatus, GpuError> {
    gpu.check_binding::<Vec3>("vertex positions", positions.len())?;
    let params = GateParams::new(capacity, GateStage::Decide, (0.0, 0.0));
    let positions = gpu.storage_buffer("positions", positions, false);
    let targets = gpu.storage_buffer("targets", targets, false);
    let selected = gpu.storage_buffer("selected", selected, false);
    let count = gpu.storage_buffer("selection count", &[selection_count], false);
    let status = gpu.storage_buffer("gate status", &[status], true);
    let pipeline = gpu.compute_pipeline("longest_move")?;
    let uniform = gpu.uniform_buffer("longest_move params", &params);
    let mut encoder = gpu.encoder("longest_move");
    gpu.record_dispatch(
        &mut encoder,
        &pipeline,
        "longest_move",
        &[&uniform, &positions, &selected, &count, &targets, &status],
        capacity,
        GATE_WORKGROUP_SIZE,
    );
    gpu.submit(encoder);
    Ok(gpu.read_buffer::<GateStatus>(&status, 1)?[0])
}

/// One `sample_gate` stage on the GPU, dispatched as the host records it; returns the
/// selection count, the moving list and the status after it.
pub fn run_sample_gate(
    gpu: &GpuContext,
    params: &GateParams,
    ring_overflows: u32,
    (selection_count, moving, status): (u32, &[MovingVertex], GateStatus),
) -> Result<(u32, Vec<MovingVertex>, GateStatus), GpuError> {
    let count = gpu.storage_buffer("selection count", &[selection_count], true);
    let overflows = gpu.storage_buffer("ring overflows", &[ring_overflows], false);
    let moving_buffer = gpu.storage_buffer("moving list", moving, true);
    let status = gpu.storage_buffer("gate status", &[status], true);
    // Unused by the stages; bound by the check alone.
    let gate = GateBuffers {
        positions: &count,
        selected: &count,
        selection_count: &count,
        targets: &count,
        ring_overflows: &overflows,
        moving: &moving_buffer,
        status: &status,
    };
    let mut encoder = gpu.encoder("sample_gate");
    record_stage(gpu, &mut encoder, &gate, params)?;
    gpu.submit(encoder);
    Ok((
        gpu.read_buffer::<u32>(&count, 1)?[0],
        gpu.read_buffer(&moving_buffer, moving.len())?,
        gpu.read_buffer::<GateStatus>(&status, 1)?[0],
    ))
}

/// Records `moved_edges` after a sample's moves: the longest edge of the faces around the
/// entries of the moving list's first `slots` that moved, folded into the run's edge bound in
/// `status`.
pub fn record_moved_edges(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (positions, topology): (&wgpu::Buffer, &wgpu::Buffer),
    vertex_rows_base: u32,
    (moving, slots): (&wgpu::Buffer, usize),
    status: &wgpu::Buffer,
) -> Result<(), GpuError> {
    let pass = MovedPass {
        kernel: "moved_edges",
        positions,
        topology,
        vertex_rows_base,
    };
    pass.record(gpu, encoder, (moving, slots), status)
}

/// `moved_edges` on the GPU over `moving`, `mesh`'s positions being where the entries are now,
/// folded into `status` and read back.
pub fn run_moved_edges(
    gpu: &GpuContext,
    mesh: &Mesh,
    moving: &[MovingVertex],
    status: GateStatus,
) -> Result<GateStatus, GpuError> {
    Ok(MovedPass::run(gpu, "moved_edges", mesh, moving, &[status])?[0])
}
