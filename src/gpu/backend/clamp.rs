//! A step's proximity passes on the GPU (the collision response's first phase, as
//! `crate::collide::clamp_moves` runs them on the CPU) and the backstop filter after them:
//! recorded over the host's moving list ([`GpuKernels::gpu_clamp`]) or, in the submission that
//! selected and deformed, over the list `moving_entries` built there, run ahead of the
//! pipeline's `clamp` ([`ClampedAhead`]) and put back when the pipeline does not take them.

use glam::Vec3;

use super::GpuKernels;
use super::hashed::{TableUse, cell_size};
use super::resident::{Resident, ResidentTopology, put_back_rows};
use super::step_buffers::{ClampRead, StepBuffers};
use crate::collide::{Backstop, MAX_PASSES, StrokeState};
use crate::gpu::{
    APPLY_WORKGROUP_SIZE, ApplyMode, ApplyMovesBuffers, ApplyParams, BackstopBuffers,
    BackstopParams, GpuContext, GpuError, PROXIMITY_WORKGROUP_SIZE, ProximityBuffers,
    ProximityParams, backstop_params, check_invocations, moved_edge_bound, moving_vertices,
    pass_params, record_apply_moves, record_backstop_filter, record_dispatch_args,
    record_proximity,
};
use crate::mesh::Mesh;
use crate::pipeline::{BackstopFilter, Uploads};

/// A merged submission's passes assume moves up to this many times the last step's longest.
pub(super) const AHEAD_MOVE_GROWTH: f32 = 2.0;

/// A step's proximity passes and filter run in the submission that selected and deformed
/// (`GpuKernels::select_deform_and_clamp`), waiting for the pipeline to clamp these moves.
pub(super) struct ClampedAhead {
    /// The selection (ascending) and its targets.
    pub(super) vertices: Vec<u32>,
    pub(super) targets: Vec<Vec3>,
    /// One per selected vertex.
    pub(super) finals: Vec<Vec3>,
    pub(super) backstop: Backstop,
    /// No passes ran: the finals are the targets, to be taken only where the host finds the
    /// step's region one layer and a clear sheet there (`collide::clamp_on_a_clear_sheet`).
    pub(super) without_passes: bool,
}

/// How a step's proximity passes are sized: `count` slots of the step's moving list, no move
/// longer than `step_move`, no edge after the step longer than `moved_edge` (read by the
/// filter only); when `counted_by` holds the selection count the slots were built from
/// (`moving_entries`), the first pass is sized from it by the GPU, vacant slots left out.
pub(super) struct PassBounds<'a> {
    pub(super) count: usize,
    pub(super) step_move: f32,
    pub(super) moved_edge: f32,
    /// How far any vertex may be from where the table filed it.
    pub(super) drift: f32,
    pub(super) counted_by: Option<&'a wgpu::Buffer>,
    /// The targets placed and gathered as finals, no passes nor filter between
    /// ([`AheadBounds::skip_passes`](super::select_deform::AheadBounds)).
    pub(super) skip_passes: bool,
}

impl GpuKernels {
    /// The proximity passes of one step on the GPU, as [`clamp_moves`](crate::collide::clamp_moves)
    /// runs them, over entries and rings the host builds (`moving_vertices`); see [`record_clamp`].
    /// Returns the final positions, and the filter's undecided pairs (or `Backstop::Gather` when it
    /// did not run or they overflowed its room). One submission, one read-back.
    pub(super) fn gpu_clamp(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        selection: &[(u32, f32)],
        targets: &[Vec3],
        before: &[Vec3],
    ) -> Result<(Vec<Vec3>, Backstop), GpuError> {
        if selection.is_empty() {
            return Ok((Vec::new(), Backstop::Undecided(Vec::new())));
        }
        self.check_injected_failure()?;
        // Calls still queued were recorded on positions before moves that were not theirs (a
        // start that deferred to steps the pipeline did not take): the passes read the mesh's.
        self.drop_queued(mesh);
        let filter = self.backstop_on_gpu;
        let (gpu, step, readback) = (&self.gpu, &mut self.step, &mut self.readback);
        let r = GpuKernels::prepare(
            gpu,
            (&mut self.resident, &mut self.uploads),
            mesh,
            cell_size(state),
            TableUse::Proximity,
        )?;
        r.ensure_topology(gpu, mesh)?;
        let vertices: Vec<u32> = selection.iter().map(|&(v, _)| v).collect();
        let (moving, rings) = moving_vertices(mesh, &vertices, before, state.ring);
        let count = moving.len();
        step.moving.upload(gpu, &moving)?;
        step.rings.upload(gpu, &rings)?;
        step.targets.upload(gpu, targets)?;
        let bounds = PassBounds {
            count,
            step_move: crate::geom::largest_move(before, targets),
            moved_edge: if filter {
                moved_edge_bound(mesh, &vertices, before, targets)
            } else {
                0.0
            },
            drift: r.hashed().drift,
            counted_by: None,
            skip_passes: false,
        };
        step.reserve_clamp(gpu, count, filter)?;
        let mut encoder = gpu.encoder("clamp");
        let read = record_clamp(gpu, &mut encoder, (r, step), state, &bounds, filter)?;
        let mut parts = vec![(step.finals.buffer(), read.finals_bytes)];
        if let Some(pair_bytes) = read.pair_bytes {
            parts.push((&step.pair_count, 4));
            parts.push((step.pairs.buffer(), pair_bytes));
        }
        let data = readback.read_back_parts(gpu, encoder, &parts)?;
        let (finals, backstop) = step.parse_clamp(&data, count, read);
        tally(&mut self.filter, &backstop, filter);
        Ok((finals, backstop))
    }

    /// The longest move passes recorded before the moves are known are sized for: twice the
    /// last step's longest move, within the step `limit` (the limit before the first).
    pub(super) fn assumed_move(&self, limit: f32) -> f32 {
        match self.last_move {
            0.0 => limit,
            last => (AHEAD_MOVE_GROWTH * last).min(limit),
        }
    }

    /// Drops the passes a merged submission ran ahead when the pipeline did not take them:
    /// the GPU's positions of those vertices go back to the mesh's. Samples queued after them
    /// were recorded on their moves, and go too.
    pub(super) fn drop_ahead(&mut self, mesh: &Mesh) {
        if let Some(ahead) = self.ahead.take() {
            self.drop_queued(mesh);
            let resident = self.resident.as_ref();
            put_back(
                &self.gpu,
                resident,
                &mut self.uploads,
                mesh,
                &ahead.vertices,
            );
        }
    }

    /// Drops whatever ran ahead — the passes of one step and the samples queued — when the
    /// pipeline asks for something else.
    pub(super) fn drop_all_ahead(&mut self, mesh: &Mesh) {
        self.drop_ahead(mesh);
        self.drop_queued(mesh);
    }
}

/// Puts the GPU's rows of `vertices` back to the mesh's where passes run ahead wrote them and
/// the pipeline did not take them (counted as dropped).
pub(super) fn put_back(
    gpu: &GpuContext,
    resident: Option<&Resident>,
    uploads: &mut Uploads,
    mesh: &Mesh,
    vertices: &[u32],
) {
    uploads.dropped_ahead += 1;
    put_back_rows(gpu, resident, mesh, vertices);
}

/// Counts what the filter left the CPU (`filter`: it ran).
pub(super) fn tally(stats: &mut BackstopFilter, backstop: &Backstop, filter: bool) {
    match backstop {
        Backstop::Undecided(pairs) => {
            stats.filtered += 1;
            stats.undecided_pairs += pairs.len();
        }
        _ if filter => stats.overflowed += 1,
        _ => {}
    }
}

/// Records the proximity passes of one step, as [`clamp_moves`](crate::collide::clamp_moves) runs
/// them, over the slots of `step.moving` (their rings in `step.ring_slots` when the GPU built them,
/// else in `step.rings`) and targets in `step.targets`: targets placed, a first pass against every
/// face, then passes against the faces pulled-back vertices moved until one pulls nothing (the GPU
/// sizes each pass from the last), the last sending what still collides back to its start; final
/// positions gathered; then, with `filter`, the backstop filter (`wgsl/backstop_filter.wgsl`) over the
/// faces that moved. Buffers reserved beforehand (`StepBuffers::reserve_clamp`); the topology
/// resident.
pub(super) fn record_clamp(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (r, step): (&Resident, &StepBuffers),
    state: &StrokeState<'_>,
    bounds: &PassBounds<'_>,
    filter: bool,
) -> Result<ClampRead, GpuError> {
    let hashed = r.hashed();
    let Some(ResidentTopology {
        buffer: topology,
        layout,
    }) = &r.topology
    else {
        unreachable!("the caller made the topology resident");
    };
    let count = bounds.count;
    let first = pass_params(
        (
            state.collision_distance,
            state.max_edge,
            bounds.drift + bounds.step_move,
        ),
        hashed.table.inv_cell_size,
        hashed.table.table_size,
        count,
        layout.vertex_rows_base,
    );
    // Vertices moved or changed since the main table was built are filed in the overlay:
    // each invocation walks its cell there too, and leaves them out of the main table.
    let overlay = hashed.overlay();
    let params = |all_faces: bool| ProximityParams {
        all_faces: all_faces as u32,
        overlay: overlay.is_some() as u32,
        overlay_mask: overlay.map_or(0, |o| o.table.table_size - 1),
        ..first
    };
    check_invocations(&params(true))?;
    let rings = match bounds.counted_by {
        Some(_) => step.ring_slots.buffer(),
        None => step.rings.buffer(),
    };
    // Without an overlay its bindings are never read: the main table's stand in.
    let proximity = ProximityBuffers {
        positions: &r.vertices.positions,
        offsets: &hashed.table.offsets,
        entries: &hashed.table.entries,
        topology,
        moving: step.moving.buffer(),
        rings,
        marks: &r.marks,
        overlay_marks: &hashed.marks,
        overlay_offsets: overlay.map_or(&hashed.table.offsets, |o| o.table.offsets),
        overlay_entries: overlay.map_or(&hashed.table.entries, |o| o.table.entries),
    };
    let apply = ApplyMovesBuffers {
        moving: step.moving.buffer(),
        targets: step.targets.buffer(),
        pulls: step.pulls.buffer(),
        positions: &r.vertices.positions,
        marks: &r.marks,
        next_count: &step.next_count,
        finals: step.finals.buffer(),
    };
    record_apply_moves(
        gpu,
        encoder,
        &apply,
        &ApplyParams::new(count, ApplyMode::Place),
        None,
    )?;
    if !bounds.skip_passes {
        let passes = (&params(true), &params(false));
        record_passes(gpu, encoder, step, (&proximity, &apply), passes, bounds)?;
    }
    record_apply_moves(
        gpu,
        encoder,
        &apply,
        &ApplyParams::new(count, ApplyMode::Gather),
        None,
    )?;
    let finals_bytes = (count * std::mem::size_of::<Vec3>()) as u64;
    if !filter || bounds.skip_passes {
        return Ok(ClampRead {
            finals_bytes,
            pair_bytes: None,
            without_passes: bounds.skip_passes,
        });
    }
    let pair_bytes = record_filter(gpu, encoder, (r, step), (&proximity, &apply), state, bounds)?;
    Ok(ClampRead {
        finals_bytes,
        pair_bytes: Some(pair_bytes),
        without_passes: false,
    })
}

/// [`record_clamp`]'s passes over the placed targets: the first with `first` (against every
/// face), the later ones with `later` (against the faces the pass before changed), at most
/// [`MAX_PASSES`], the last sending what still collides back to its start.
fn record_passes(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    step: &StepBuffers,
    (proximity, apply): (&ProximityBuffers<'_>, &ApplyMovesBuffers<'_>),
    (first, later): (&ProximityParams, &ProximityParams),
    bounds: &PassBounds<'_>,
) -> Result<(), GpuError> {
    let count = bounds.count;
    let invocations = count * first.cells_per_entry as usize;
    let pulls = step.pulls.buffer();
    let apply_params = |mode| ApplyParams {
        next_invocations: invocations as u32,
        ..ApplyParams::new(count, mode)
    };
    for pass in 0..MAX_PASSES {
        // The first pass is sized by the host, or from the selection count; later ones by the
        // pass before, so that they shrink to nothing once a pass pulls nothing back.
        let (sized, apply_sized) = match (pass, bounds.counted_by) {
            (0, None) => (None, None),
            (0, Some(selection_count)) => {
                record_dispatch_args(
                    gpu,
                    encoder,
                    selection_count,
                    (count, first.cells_per_entry),
                    PROXIMITY_WORKGROUP_SIZE,
                    &step.pass_args,
                )?;
                (Some(&step.pass_args), None)
            }
            _ => (Some(&step.pass_args), Some(&step.apply_args)),
        };
        let params = if pass == 0 { first } else { later };
        record_proximity(gpu, encoder, proximity, params, pulls, sized)?;
        encoder.clear_buffer(&step.next_count, 0, None);
        let mode = if pass + 1 == MAX_PASSES {
            ApplyMode::PullLast
        } else {
            ApplyMode::Pull
        };
        record_apply_moves(gpu, encoder, apply, &apply_params(mode), apply_sized)?;
        // Both sizes from the one count: all invocations, or none after a quiet pass.
        record_dispatch_args(
            gpu,
            encoder,
            &step.next_count,
            (invocations, 1),
            PROXIMITY_WORKGROUP_SIZE,
            &step.pass_args,
        )?;
        record_dispatch_args(
            gpu,
            encoder,
            &step.next_count,
            (count, 1),
            APPLY_WORKGROUP_SIZE,
            &step.apply_args,
        )?;
    }
    Ok(())
}

/// [`record_clamp`]'s backstop filter (`wgsl/backstop_filter.wgsl`) over the faces that moved, after
/// the passes: the pairs it cannot clear go to `step.pairs`, within room for
/// `step.pair_capacity` of them. Returns the bytes of that room.
fn record_filter(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (r, step): (&Resident, &StepBuffers),
    (proximity, apply): (&ProximityBuffers<'_>, &ApplyMovesBuffers<'_>),
    state: &StrokeState<'_>,
    bounds: &PassBounds<'_>,
) -> Result<u64, GpuError> {
    let hashed = r.hashed();
    let overlay = hashed.overlay();
    let Some(ResidentTopology {
        buffer: topology,
        layout,
    }) = &r.topology
    else {
        unreachable!("the caller made the topology resident");
    };
    let count = bounds.count;
    let capacity = step.pair_capacity;
    let params = BackstopParams {
        overlay: overlay.is_some() as u32,
        overlay_mask: overlay.map_or(0, |o| o.table.table_size - 1),
        ..backstop_params(
            (state.max_edge, bounds.moved_edge),
            (bounds.drift, bounds.step_move),
            (hashed.table.inv_cell_size, hashed.table.table_size),
            count,
            layout.vertex_rows_base,
            capacity,
        )
    };
    // The map from vertex to moved entry lives in the marks for the filter's while.
    record_apply_moves(
        gpu,
        encoder,
        apply,
        &ApplyParams::new(count, ApplyMode::MarkMoved),
        None,
    )?;
    encoder.clear_buffer(&step.pair_count, 0, None);
    record_backstop_filter(
        gpu,
        encoder,
        &BackstopBuffers {
            positions: &r.vertices.positions,
            offsets: &hashed.table.offsets,
            entries: &hashed.table.entries,
            topology,
            moving: step.moving.buffer(),
            moved: &r.marks,
            overlay_marks: &hashed.marks,
            overlay_offsets: proximity.overlay_offsets,
            overlay_entries: proximity.overlay_entries,
        },
        &params,
        (step.pairs.buffer(), &step.pair_count),
    )?;
    record_apply_moves(
        gpu,
        encoder,
        apply,
        &ApplyParams::new(count, ApplyMode::Clear),
        None,
    )?;
    Ok((capacity * std::mem::size_of::<[u32; 2]>()) as u64)
}
