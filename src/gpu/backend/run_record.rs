//! How a run of samples recorded ahead is laid out and recorded (`super::run_ahead` queues
//! what it leaves): the calls it records ([`RunCall`]) — samples' starts, the steps of a sample
//! of several, and the split steps a start may defer its move to — how each call's passes are
//! sized ([`RunShape`]: the assumed move, and the edges' growth, raised by the runs before on
//! the same mesh that measured more), and the one submission that records them all and reads
//! their results back ([`record_run`]).

use super::resident::Resident;
use super::select_deform::{AheadBounds, CallFrame, RecordedSample, SampleLayout, record_sample};
use super::step_buffers::StepBuffers;
use crate::brush::{Dab, move_bound};
use crate::collide::StrokeState;
use crate::cpu::FRAME_SUM_WORDS;
use crate::gpu::reusable::ReusableBuffer;
use crate::gpu::{
    GateBuffers, GateSplit, GpuContext, GpuError, MovingVertex, SelectedVertex, record_gate_vacate,
    record_moved_edges, record_moved_normals,
};
use crate::pipeline::SampleProbe;

/// A planned sample whose move may be over the step limit has the two steps of a move over it
/// by at most twice recorded right after its start: the bench strokes' samples of several
/// steps took two, and none could be told from its settings before it ran (all flattens).
pub(super) const SPLIT_STEPS: usize = 2;

/// A run's later samples assume the mesh's longest edge grows by at most a share of the
/// assumed move per sample before them, at most this one; the gate stops the run at the first
/// whose edges, as `moved_edges` measured them, say otherwise (and the host drops it should the
/// pipeline's own bound disagree). A step lengthens an edge by at most twice its longest move,
/// but the passes' reach grows with the edge bound (their work with its cube): plaster at 2K
/// faces, steps of a cell, grew its longest edge by 0 to 0.32 of the step limit a sample;
/// assuming the worst case (2) made a run of four samples cost three times one assuming this
/// share.
pub(super) const EDGE_GROWTH_AHEAD: f32 = 0.5;

/// The share a run assumes on a new mesh. A run that measures the edges grown by more (the
/// gate's bound, before its last call) raises it to twice that, within [`EDGE_GROWTH_AHEAD`],
/// for the runs after it on the same mesh: runs that split their samples of two steps stop less
/// and so run longer, and the bound grows with their length. On lavapipe, the bench's bark
/// strokes took 2.50, 2.25 and 2.17 s a sample at fixed shares of 0.5, 0.25 and 0.125 (the
/// gate stopping for the edges at none), while plaster's stopped for the edges at 1, 13 and 18
/// of its 57 samples.
pub(super) const EDGE_GROWTH_LEAST: f32 = 0.125;

/// What a run records at one place, and what the pipeline's call for it must be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum RunCall {
    /// Planned sample `index` from its start: its selection, brush frame and whole
    /// deformation (`select_deform_and_clamp` with the sample's probe), and the passes of its
    /// one step.
    Start(usize),
    /// Step `k` of the `steps` of the stroke's sample numbered `sample`, each under `dab` (the
    /// sample's frame, a share of its move): selected again and deformed, with the step's
    /// passes. The pipeline asks for step 0 with `deform` on the sample's selection, and for
    /// the later ones with `select_deform_and_clamp` under the dab.
    Step {
        sample: usize,
        dab: Dab,
        k: usize,
        steps: usize,
    },
    /// Step `k` of the [`SPLIT_STEPS`] planned sample `index` takes when its move is over the
    /// step limit by at most twice, recorded right after its start, which then defers its move
    /// to them; each step moves only when it did. Its frame is the one the start summed.
    SplitStep { index: usize, k: usize },
}

impl RunCall {
    /// The dab the call is recorded under, and where its frame comes from (`plan`: the
    /// stroke's planned samples).
    pub(super) fn dab_and_frame(self, plan: &[SampleProbe]) -> (Dab, CallFrame) {
        match self {
            RunCall::Start(index) => {
                let (dab, normal) = plan[index];
                (dab, CallFrame::Summed { normal })
            }
            RunCall::Step { dab, .. } => (dab, CallFrame::Dab),
            RunCall::SplitStep { index, .. } => {
                let (dab, normal) = plan[index];
                let dab = Dab {
                    share: 1.0 / SPLIT_STEPS as f32,
                    ..dab
                };
                (dab, CallFrame::SummedAtStart { normal })
            }
        }
    }

    /// How the call at `j` of `calls` stands to a sample that may defer its move: a start
    /// followed by its split steps defers over `limit`.
    fn split(calls: &[RunCall], j: usize, limit: f32) -> GateSplit {
        match (calls[j], calls.get(j + 1)) {
            (RunCall::SplitStep { .. }, _) => GateSplit {
                defer_over: 0.0,
                if_deferred: true,
            },
            (RunCall::Start(_), Some(RunCall::SplitStep { .. })) => GateSplit {
                defer_over: limit,
                if_deferred: false,
            },
            _ => GateSplit::default(),
        }
    }

    /// The longest move the call's passes are sized for: a split step's is at most the step
    /// limit, the others' the run's `assumed_move`.
    pub(super) fn assumed_move(self, assumed_move: f32, limit: f32) -> f32 {
        match self {
            RunCall::SplitStep { .. } => limit,
            _ => assumed_move,
        }
    }
}

/// Whether a planned sample's move may be over the step `limit`, as far as its settings tell.
pub(super) fn may_take_steps(dab: &Dab, limit: f32) -> bool {
    move_bound(dab).is_none_or(|bound| bound > limit)
}

/// How a run is recorded: `count` calls, each over `guess` slots of the selection list, their
/// passes sized by `ahead` (`filter`: with the backstop filter) but a split step's, sized for
/// the step `limit`.
pub(super) struct RunShape {
    pub(super) count: usize,
    pub(super) guess: usize,
    pub(super) ahead: AheadBounds,
    pub(super) filter: bool,
    pub(super) limit: f32,
    /// The share of the assumed move the edges are assumed to grow by per sample.
    pub(super) edge_growth: f32,
}

impl RunShape {
    /// The bounds call `j` of `calls` is recorded with.
    fn call_bounds(&self, calls: &[RunCall], j: usize) -> AheadBounds {
        AheadBounds {
            assumed_move: calls[j].assumed_move(self.ahead.assumed_move, self.limit),
            split: RunCall::split(calls, j, self.limit),
            ..self.ahead
        }
    }

    /// The bytes of a call's head of the selection list.
    fn list_bytes(&self) -> u64 {
        (self.guess * std::mem::size_of::<SelectedVertex>()) as u64
    }

    /// The bytes of a call's moving list.
    fn moving_bytes(&self) -> u64 {
        (self.guess * std::mem::size_of::<MovingVertex>()) as u64
    }
    /// The edges as the calls of a run before call `j` may have lengthened them, from the
    /// pipeline's bound `max_edge` at its start (checked by the gate, and by the host when the
    /// pipeline reaches it).
    pub(super) fn edge_bound(&self, max_edge: f32, (calls, j): (&[RunCall], usize)) -> f32 {
        let moves = moves_before(calls, j);
        max_edge + self.edge_growth * moves as f32 * self.ahead.assumed_move
    }

    /// The share to assume in the next run, from the bound on the edges the gate measured
    /// before call `j` (`edge`) and the pipeline's at the run's start (`max_edge`): twice what
    /// the calls before `j` grew them by, when that is more than this run's (within
    /// [`EDGE_GROWTH_AHEAD`]).
    pub(super) fn next_edge_growth(
        &self,
        (max_edge, edge): (f32, f32),
        (calls, j): (&[RunCall], usize),
    ) -> f32 {
        let moves = moves_before(calls, j) as f32 * self.ahead.assumed_move;
        let grown = 2.0 * (edge - max_edge) / moves;
        match grown.is_finite() && moves > 0.0 {
            true => grown.min(EDGE_GROWTH_AHEAD).max(self.edge_growth),
            false => self.edge_growth,
        }
    }
}

/// The calls before call `j` of `calls` that may move the mesh. A start and its split steps
/// count as one: either the start moves or its steps do, by as much in all.
fn moves_before(calls: &[RunCall], j: usize) -> usize {
    calls[..j]
        .iter()
        .filter(|call| !matches!(call, RunCall::SplitStep { .. }))
        .count()
}

/// Records a run's `calls` (see [`GpuKernels::gpu_run_ahead`]) in one submission — the
/// overlay table rebuilt from its slots first, the gate started, each call's results copied
/// aside — submits it and maps them all. Returns the bytes, each call's layout, and the stride
/// between calls.
pub(super) fn record_run(
    gpu: &GpuContext,
    (r, step, readback): (&Resident, &StepBuffers, &mut ReusableBuffer),
    state: &StrokeState<'_>,
    (calls, plan): (&[RunCall], &[SampleProbe]),
    shape: &RunShape,
) -> Result<(Vec<u8>, Vec<SampleLayout>, u64), GpuError> {
    let count = shape.count;
    let list_bytes = shape.list_bytes();
    let mut encoder = gpu.encoder("samples ahead");
    r.hashed().record_gpu_table(gpu, &mut encoder)?;
    // The gate's edge bound starts at the pipeline's; each call but the last grows it by
    // the faces it turned (`moved_edges`) for the next one's verdict.
    step.start_gate(gpu, state.max_edge);
    let mut layouts = Vec::with_capacity(count);
    let mut stride = 0;
    for (j, &call) in calls.iter().enumerate() {
        let (dab, frame) = call.dab_and_frame(plan);
        let state = StrokeState {
            max_edge: shape.edge_bound(state.max_edge, (calls, j)),
            ..*state
        };
        let ahead = shape.call_bounds(calls, j);
        let recorded = record_call(
            gpu,
            &mut encoder,
            (r, step),
            &state,
            (j, call, &dab, frame),
            (shape, ahead),
        )?;
        let mut parts = vec![(&r.selection.count, 4), (&r.selection.selected, list_bytes)];
        parts.extend_from_slice(&recorded.parts);
        if j == 0 {
            // Every call leaves the same parts, but for the brush frame's sums a step
            // (whose frame is its dab's) leaves out: room for the largest.
            let frame_bytes = match recorded.layout.frame_from_selection {
                Some(_) => 0,
                None => (FRAME_SUM_WORDS * 4) as u64,
            };
            stride = parts.iter().map(|&(_, bytes)| bytes).sum::<u64>() + frame_bytes;
            readback.reserve(gpu, stride * count as u64)?;
        }
        layouts.push(recorded.layout);
        readback.record_copies(&mut encoder, &parts, j as u64 * stride);
    }
    let data = readback.submit_and_map(gpu, encoder, stride * count as u64)?;
    Ok((data, layouts, stride))
}

/// Records call `j` of a run under `dab`: its step ([`record_sample`]); the normals its moves
/// turned (for a step of a sample of several, those of all its steps after the last); and, but
/// for the run's last call, the edges it lengthened (`moved_edges`, for the next call's gate)
/// and the filing of its moved vertices in the overlay.
fn record_call<'b>(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (r, step): (&'b Resident, &'b StepBuffers),
    state: &StrokeState<'_>,
    (j, call, dab, frame): (usize, RunCall, &Dab, CallFrame),
    (shape, ahead): (&RunShape, AheadBounds),
) -> Result<RecordedSample<'b>, GpuError> {
    let Some(topology) = &r.topology else {
        unreachable!("reserve_sample made the topology resident");
    };
    let (guess, moving_bytes) = (shape.guess, shape.moving_bytes());
    let recorded = record_sample(
        gpu,
        encoder,
        (r, step),
        state,
        dab,
        (frame, true),
        guess,
        Some(ahead),
        shape.filter,
    )?;
    let steps_of = match call {
        RunCall::Start(_) => None,
        RunCall::Step { k, steps, .. } => Some((k, steps)),
        RunCall::SplitStep { k, .. } => Some((k, SPLIT_STEPS)),
    };
    let normals_of = match steps_of {
        None => Some((step.moving.buffer(), guess)),
        // The pipeline recomputes normals after a sample's last step: every step
        // deforms on the normals from before the sample. Each step's moving list is
        // kept until then, and vacated if the run stopped at one of them (or, for split
        // steps, if their sample did not defer): the steps taken before the stop leave
        // their normals to the pipeline.
        Some((k, steps)) => {
            let held = step.held_moving.buffer();
            encoder.copy_buffer_to_buffer(
                step.moving.buffer(),
                0,
                held,
                k as u64 * moving_bytes,
                moving_bytes,
            );
            let last = k + 1 == steps;
            if last {
                record_gate_vacate(
                    gpu,
                    encoder,
                    &GateBuffers {
                        moving: held,
                        ..step.gate(r)
                    },
                    steps * guess,
                    ahead.split,
                )?;
            }
            last.then_some((held, steps * guess))
        }
    };
    if let Some(moving) = normals_of {
        record_moved_normals(
            gpu,
            encoder,
            (&r.vertices.positions, &topology.buffer),
            topology.layout.vertex_rows_base,
            moving,
            &r.normals,
        )?;
    }
    if j + 1 < shape.count {
        record_moved_edges(
            gpu,
            encoder,
            (&r.vertices.positions, &topology.buffer),
            topology.layout.vertex_rows_base,
            (step.moving.buffer(), guess),
            &step.gate_status,
        )?;
        r.hashed().record_gpu_filing(
            gpu,
            encoder,
            &r.vertices.positions,
            (step.moving.buffer(), guess),
        )?;
    }
    Ok(recorded)
}
