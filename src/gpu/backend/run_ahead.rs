//! A stroke's samples recorded ahead, several in one submission. The pipeline gives the
//! kernels the samples of its current call ([`StepKernels::given`]), and names each call by
//! its sample's number in the stroke ([`CallAt`]), never by its dab; at a sample's start the
//! kernels record that sample and the next ones one after another — each one's selection,
//! brush frame, deformation, moving entries, proximity passes, backstop filter, the normals
//! its moves turned (`moved_normals`) and the filing of its moved vertices in the hash table's
//! overlay (`overlay_members`, then the overlay rebuilt from its slots), each reading the
//! positions, normals and table the one before left on the GPU — copy each one's results
//! aside, and read them all back in one map. The pipeline then takes them one by one as if each
//! had been a submission of its own. Because each sample files what it moved, every sample of a
//! run queries the table with the first one's drift, however long the run.
//!
//! What the GPU ran is what the pipeline would have asked for only while its predictions
//! hold. Those the GPU can see are checked there, by the run's gate (`longest_move`,
//! `sample_gate`, with `moved_edges` after each sample): each sample's selection within the
//! guessed list, its rings within their room, its longest move within the one its passes were
//! sized for, and the edges the samples before it left within the bound they were sized for.
//! The first sample where one fails stops the run before it moves anything, and the samples
//! after it select nothing; the pipeline takes the samples before it and goes on one
//! submission per step from there. The host checks the move and the edges again in its own
//! arithmetic when the pipeline reaches a sample, and the exact backstop's verdict when the
//! pipeline reports the sample's moves (it must undo nothing). From the first sample where one
//! of those fails, the rest are dropped: the rows they wrote go back to the mesh's (positions,
//! and the normals around them).
//!
//! A sample that moves farther than a step takes several, each a share of its move, and the
//! step count is known only from its whole move. The gate stops a run at the start of such a
//! sample; what that start read (its selection, frame and whole move: nothing moved since)
//! answers the pipeline's call for it, and the pipeline's call for its first step records its
//! steps and the samples after it in the next run ([`RunCall::Step`]). Each step deforms on the
//! normals from before the sample, as the pipeline's do; the normals its moves turned are
//! recomputed after its last step.
//!
//! [`StepKernels::given`]: crate::pipeline::StepKernels::given

use std::collections::VecDeque;

use glam::Vec3;

use super::GpuKernels;
use super::clamp::ClampedAhead;
use super::hashed::{TableUse, cell_size};
use super::resident::{Resident, put_back_rows};
use super::select_deform::{
    AheadBounds, RecordedSample, SampleLayout, in_vertex_order, permuted, record_sample,
    selection_guess,
};
use super::step_buffers::StepBuffers;
use crate::brush::Dab;
use crate::collide::StrokeState;
use crate::cpu::FRAME_SUM_WORDS;
use crate::gpu::reusable::ReusableBuffer;
use crate::gpu::{
    GateBuffers, GateStatus, GpuContext, GpuError, MovingVertex, SelectedVertex,
    record_gate_vacate, record_moved_edges, record_moved_normals, ring_bytes,
};
use crate::mesh::Mesh;
use crate::pipeline::step::longest_move;
use crate::pipeline::{CallAt, Deformed, FrameSource, SampleProbe};

/// At most this many samples in one submission: the read-back grows with each, and each later
/// sample's passes are sized for edges grown by [`EDGE_GROWTH_AHEAD`] per sample before it, so
/// their reach grows with the run. A run records every sample given from where it starts, up
/// to this many: a stroke given whole costs one blocking read-back per run, one more per gate
/// stop. A run the gate stops still has the GPU go through the recorded passes of every sample
/// after the stop, emptied but dispatched (a fixed cost per dispatch on a hardware GPU); runs
/// that started at two samples and doubled spent fewer such dispatches but read back 4 times
/// where this reads back once or twice (`docs/gpu.md`).
pub(super) const MAX_SAMPLES_AHEAD: usize = 32;

/// A sample of at most this many steps has them recorded in a run (each step's moving list
/// is kept until the sample's last, for the normals): the bench strokes took at most 3.
pub(super) const MAX_STEPS_AHEAD: usize = 8;

/// A run's later samples assume the mesh's longest edge grows by at most this share of the
/// assumed move per sample before them; the gate stops the run at the first whose edges, as
/// `moved_edges` measured them, say otherwise (and the host drops it should the pipeline's own
/// bound disagree). A step lengthens an edge by at most twice its longest move, but the
/// passes' reach grows with the edge bound (their work with its cube): plaster at 2K faces,
/// steps of a cell, grew its longest edge by 0 to 0.32 of the step limit a sample; assuming the
/// worst case (2) made a run of four samples cost three times one assuming this share. With the
/// gate, 0.25 stopped the run-ahead test's runs once more for the same lavapipe time.
const EDGE_GROWTH_AHEAD: f32 = 0.5;

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
}

impl RunCall {
    /// The dab the call is recorded under, and where its frame comes from (`plan`: the
    /// stroke's planned samples).
    fn dab_and_source(self, plan: &[SampleProbe]) -> (Dab, FrameSource) {
        match self {
            RunCall::Start(index) => {
                let (dab, normal) = plan[index];
                (dab, FrameSource::Selection { normal })
            }
            RunCall::Step { dab, .. } => (dab, FrameSource::Dab),
        }
    }
}

/// A sample start or step recorded ahead, waiting for the pipeline to reach it.
pub(super) struct QueuedCall {
    call: RunCall,
    deformed: Deformed,
    /// The step's passes; `None` when nothing was selected, or at the start of a sample of
    /// several steps the gate stopped (its passes moved nothing; its steps are recorded when
    /// the pipeline asks for the first).
    ahead: Option<ClampedAhead>,
    /// The longest move the passes were sized for.
    assumed_move: f32,
    /// The bound on the mesh's edges at the step's start the passes were sized for.
    max_edge: f32,
    /// Its moved vertices were filed in the overlay on the GPU (every call of a run but the
    /// last).
    filed: bool,
}

/// The vertices a queued call's passes may have moved.
fn moved_by(queued: &QueuedCall) -> &[u32] {
    queued.ahead.as_ref().map_or(&[], |a| a.vertices.as_slice())
}

impl GpuKernels {
    /// Where the stroke's sample numbered `sample` is among the samples given, if it is.
    pub(super) fn plan_index(&self, sample: usize) -> Option<usize> {
        let index = sample.checked_sub(self.plan_first)?;
        (index < self.plan.len()).then_some(index)
    }

    /// Whether a run may start at planned sample `at`: runs ahead on, not the last of the plan (a run of one
    /// sample is a single step), not one a run reached already (its queued start was dropped
    /// for moving farther than assumed), nor one that stopped a run where the next would stop
    /// too ([`GpuKernels::after_stop`]).
    pub(super) fn may_start_run(&self, at: usize) -> bool {
        self.runs_ahead()
            && at + 1 < self.plan.len()
            && at >= self.plan_next
            && Some(at) != self.no_run_at
    }

    /// Whether runs ahead are recorded at all: the passes on the GPU, run ahead of the
    /// pipeline's clamp, and the GPU not given up.
    pub(super) fn runs_ahead(&self) -> bool {
        self.proximity_on_gpu && self.clamp_ahead && self.run_ahead && self.failed.is_none()
    }

    /// Records in one submission the `steps` of a sample of several (all under its dab) when
    /// given, then the given samples from `from` (at most [`MAX_SAMPLES_AHEAD`]), and queues what each left for the pipeline; nothing when that
    /// is fewer than two. The passes are sized as a single step's would be (`assumed_move`:
    /// twice the last move, within `limit`), each later call's from edges grown by
    /// [`EDGE_GROWTH_AHEAD`] of that move per call before it.
    pub(super) fn gpu_run_ahead(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        (steps, from): (Option<(usize, Dab, usize)>, Option<usize>),
        limit: f32,
    ) -> Result<(), GpuError> {
        self.check_injected_failure()?;
        self.check_gpu_filing(mesh);
        self.drop_all_ahead(mesh);
        let (calls, step_count) = self.run_calls(steps, from);
        let count = calls.len();
        let filter = self.backstop_on_gpu;
        let assumed_move = self.assumed_move(limit);
        let (gpu, step, readback) = (&self.gpu, &mut self.step, &mut self.readback);
        let r = GpuKernels::prepare(
            gpu,
            (&mut self.resident, &mut self.uploads),
            mesh,
            cell_size(state),
            TableUse::Proximity,
        )?;
        let capacity = r.selection.capacity;
        let guess = selection_guess(self.last_selection, capacity);
        // Each call's moved vertices are filed in the overlay on the GPU before the next
        // (`Hashed::record_gpu_filing`): every call queries with the drift of the first.
        let drift = r.hashed().drift;
        let moving_bytes = (guess * std::mem::size_of::<MovingVertex>()) as u64;
        // The rings of the guessed slots, and the moving lists the steps keep, must each fit
        // one binding.
        let binding = gpu.limits.max_storage_buffer_binding_size;
        if count < 2 || ring_bytes(guess) > binding || step_count as u64 * moving_bytes > binding {
            return Ok(());
        }
        step.reserve_sample(gpu, (r, mesh), guess, true, true, filter)?;
        step.held_moving
            .reserve(gpu, step_count as u64 * moving_bytes)?;
        // Room for the overlay's members and for every slot of the moving lists of the calls
        // that file theirs (all but the last); no more than the vertices there are.
        let room = (r.hashed().overlay.as_ref().map_or(0, |o| o.members.len())
            + (count - 1) * guess)
            .min(r.vertices.count);
        let Some(hashed) = &mut r.hashed else {
            unreachable!("prepare built the hash table");
        };
        hashed.start_gpu_filing(gpu, room)?;
        let shape = RunShape {
            count,
            guess,
            ahead: AheadBounds {
                assumed_move,
                drift,
            },
            filter,
        };
        let run = (calls.as_slice(), self.plan.as_slice());
        let (data, layouts, stride) = record_run(gpu, (&*r, step, readback), state, run, &shape)?;
        self.uploads.batches += 1;
        let read = (data.as_slice(), layouts.as_slice(), stride);
        self.queue_run(read, &calls, state.max_edge, &shape, (capacity, limit));
        Ok(())
    }

    /// The calls of a run: the `steps` of a sample of several when given, then the given
    /// samples from `from` (at most [`MAX_SAMPLES_AHEAD`]); and how many of them are steps.
    fn run_calls(
        &self,
        steps: Option<(usize, Dab, usize)>,
        from: Option<usize>,
    ) -> (Vec<RunCall>, usize) {
        let mut calls: Vec<RunCall> = steps
            .into_iter()
            .flat_map(|(sample, dab, steps)| {
                (0..steps).map(move |k| RunCall::Step {
                    sample,
                    dab,
                    k,
                    steps,
                })
            })
            .collect();
        let step_count = calls.len();
        if let Some(from) = from {
            let samples = (self.plan.len() - from).min(MAX_SAMPLES_AHEAD);
            calls.extend((from..from + samples).map(RunCall::Start));
        }
        (calls, step_count)
    }

    /// Queues what each of a run's `calls` left for the pipeline — `data`, `stride` bytes a
    /// call, split as `layouts` — up to the call where the gate stopped the run (that one too
    /// when the pipeline's call for it is answered from here, [`GpuKernels::after_stop`]), and
    /// notes what the GPU filed for the host's next filing. `max_edge`: the pipeline's bound
    /// on the edges at the run's start; `capacity`: the selection list's; `limit`: the step
    /// limit.
    fn queue_run(
        &mut self,
        (data, layouts, stride): (&[u8], &[SampleLayout], u64),
        calls: &[RunCall],
        max_edge: f32,
        shape: &RunShape,
        (capacity, limit): (usize, f32),
    ) {
        let (count, guess) = (shape.count, shape.guess);
        let assumed_move = shape.ahead.assumed_move;
        let list_bytes = shape.list_bytes();
        // What the GPU filed, for the host's next filing to hold too.
        let mut filed_on_gpu = Vec::new();
        for (j, bytes) in data.chunks_exact(stride as usize).enumerate() {
            let found = (u32::from_le_bytes(bytes[..4].try_into().expect("four bytes")) as usize)
                .min(capacity);
            self.last_selection = self.last_selection.max(found);
            let head = found.min(guess);
            let list: Vec<SelectedVertex> = bytemuck::pod_collect_to_vec(&bytes[4..4 + 8 * head]);
            let call = calls[j];
            let (dab, _) = call.dab_and_source(&self.plan);
            let layout = layouts[j];
            let parts = layout.split(&bytes[4 + list_bytes as usize..], &dab);
            let status = parts.gate.expect("runs go through the gate");
            let (order, selection) = in_vertex_order(&list);
            let targets = |found: usize| -> Vec<Vec3> {
                permuted(
                    &order,
                    &bytemuck::pod_collect_to_vec(&parts.targets[..found * 12]),
                )
            };
            let mut queued = QueuedCall {
                call,
                deformed: Deformed {
                    targets: None,
                    selection,
                    frame: parts.frame,
                    deform_millis: 0.0,
                },
                ahead: None,
                assumed_move,
                max_edge: edge_bound(max_edge, assumed_move, j),
                filed: j + 1 < count,
            };
            if status.stopped != 0 {
                // The gate stopped the run here, before this call moved anything, and the
                // calls after it selected nothing: there is nothing to put back.
                let longest = status.longest_move();
                self.uploads.count_gate_stop(status.stopped, longest, limit);
                if let RunCall::Start(index) = call
                    && self.after_stop(index, status, limit)
                {
                    // Its selection and whole move hold (nothing moved since): the pipeline's
                    // call for it is answered from here, and its steps recorded when it asks
                    // for the first.
                    queued.deformed.targets = Some(targets(found));
                    queued.filed = false;
                    self.queued.push_back(queued);
                }
                break;
            }
            if j + 1 < count {
                filed_on_gpu.extend(list.iter().map(|s| s.vertex));
            }
            // The gate stops a run on a cut list or cut rings (the same count and buffer).
            debug_assert!(found <= guess && parts.ring_overflows == Some(0));
            if !queued.deformed.selection.is_empty() {
                let targets = targets(found);
                let clamp = layout.clamp.expect("passes recorded");
                let (finals, backstop) = self.step.parse_clamp(parts.clamp, guess, clamp);
                queued.deformed.targets = Some(targets.clone());
                queued.ahead = Some(ClampedAhead {
                    vertices: queued.deformed.selection.iter().map(|&(v, _)| v).collect(),
                    targets,
                    finals: permuted(&order, &finals),
                    backstop,
                });
            }
            self.queued.push_back(queued);
        }
        if let Some(hashed) = self.resident.as_mut().and_then(|r| r.hashed.as_mut()) {
            hashed.moved.extend_from_slice(&filed_on_gpu);
        }
    }

    /// The first step of the stroke's sample numbered `sample`, of `steps`, under `dab` (given
    /// at `planned`), on the sample's `selection`: records the sample's steps and the given
    /// samples after it in one run and takes the first step's targets from it. `None` when the
    /// sample was not given or runs ahead are off (a grab deforms what its first sample caught
    /// at every step; remeshing between samples), when the steps are too many, or when the
    /// run does not give the step.
    pub(super) fn run_steps_ahead(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        (dab, selection): (&Dab, &[(u32, f32)]),
        ((sample, steps), planned): ((usize, usize), Option<usize>),
        limit: f32,
    ) -> Option<Vec<Vec3>> {
        let at = planned.filter(|_| self.runs_ahead())?;
        if !(2..=MAX_STEPS_AHEAD).contains(&steps) {
            return None;
        }
        let from = Some(at + 1).filter(|&next| next < self.plan.len());
        let run = (Some((sample, *dab, steps)), from);
        self.on_gpu(|k| k.gpu_run_ahead(state, mesh, run, limit))?;
        let first = CallAt::Step {
            sample,
            k: 0,
            steps,
        };
        self.take_queued_step(mesh, (first, Some(selection)), state.max_edge)?
            .targets
    }

    /// After the gate stopped a run at the start of planned sample `index`: whether the
    /// pipeline's call for it is answered from what the run read (returns `true`), and whether
    /// that call starts the next run. One whose selection outgrew the guessed list, whose edges
    /// the samples before grew past the prediction, or whose move outgrew the assumed one
    /// within a step starts the next run, sized from what this run read (the list's count, the
    /// pipeline's edges, the move: `last_move`). One whose rings outgrow their fixed room would
    /// stop it again: the pipeline takes it one submission per step. One that only moves
    /// farther than a step takes several: its start is answered from here, and its first step
    /// records its steps and the samples after it in the next run.
    fn after_stop(&mut self, index: usize, status: GateStatus, limit: f32) -> bool {
        let longest = status.longest_move();
        let moved_too_far = status.stopped & GateStatus::MOVE != 0;
        if moved_too_far && longest.is_finite() {
            self.last_move = longest;
        }
        // A NaN move is not within the limit either.
        let one_step = longest <= limit;
        let several_steps = moved_too_far && !one_step;
        if status.stopped & GateStatus::RINGS != 0 || several_steps {
            self.no_run_at = Some(index);
        }
        status.stopped == GateStatus::MOVE && several_steps && longest.is_finite()
    }

    /// The queued start of the given sample at `planned` (see [`GpuKernels::take_queued`]).
    pub(super) fn take_queued_start(
        &mut self,
        mesh: &Mesh,
        planned: Option<usize>,
        max_edge: f32,
    ) -> Option<Deformed> {
        let is_start = self.queued.front().is_some_and(
            |head| matches!(head.call, RunCall::Start(index) if Some(index) == planned),
        );
        self.take_queued(mesh, is_start, max_edge)
    }

    /// The queued step the pipeline asks for at `at`: the first of a sample of several,
    /// deformed on the sample's `selection` (found again on the GPU: it must come out the
    /// same), or a later one (see [`GpuKernels::take_queued`]).
    pub(super) fn take_queued_step(
        &mut self,
        mesh: &Mesh,
        (at, selection): (CallAt, Option<&[(u32, f32)]>),
        max_edge: f32,
    ) -> Option<Deformed> {
        let is_step = self.queued.front().is_some_and(|head| match head.call {
            RunCall::Step {
                sample, k, steps, ..
            } => {
                at == CallAt::Step { sample, k, steps }
                    && selection.is_none_or(|selection| head.deformed.selection == selection)
            }
            RunCall::Start(_) => false,
        });
        self.take_queued(mesh, is_step, max_edge)
    }

    /// The queued call at the head, when the pipeline's call is it (`is_call`), its moves are
    /// one step within what its passes assumed from where the mesh is now, and the pipeline's
    /// bound on the edges (`max_edge`) within theirs. Any other call, or moves or edges past
    /// the assumption, drop the queue.
    fn take_queued(&mut self, mesh: &Mesh, is_call: bool, max_edge: f32) -> Option<Deformed> {
        if self.failed.is_some() {
            self.queued.clear();
            return None;
        }
        let head = self.queued.front()?;
        // A NaN bound does not fit either.
        let edges_fit = max_edge <= head.max_edge;
        if !is_call || !edges_fit {
            self.drop_queued(mesh);
            return None;
        }
        let longest = head
            .ahead
            .as_ref()
            .map(|ahead| longest_move(mesh, &head.deformed.selection, &ahead.targets));
        if let RunCall::Start(index) = head.call {
            self.plan_next = self.plan_next.max(index + 1);
        }
        if let Some(longest) = longest {
            self.last_move = longest;
            // A NaN move does not fit either.
            let fits = longest <= head.assumed_move;
            if !fits {
                self.drop_queued(mesh);
                return None;
            }
        }
        let queued = self.queued.pop_front()?;
        match queued.call {
            RunCall::Start(_) => self.uploads.samples_ahead += 1,
            RunCall::Step { .. } => {
                self.uploads.steps_ahead += 1;
                self.steps_taken.extend_from_slice(moved_by(&queued));
            }
        }
        self.ahead = queued.ahead;
        self.taken_filed = queued.filed;
        Some(queued.deformed)
    }

    /// Drops every queued call: the rows their passes wrote go back to the mesh's. When a
    /// step goes, so do the normals the run recomputed after the sample's last step around
    /// the steps of it taken before.
    pub(super) fn drop_queued(&mut self, mesh: &Mesh) {
        self.drop_queued_and(mesh, &[]);
    }

    /// [`GpuKernels::drop_queued`], putting back the rows of `also` too.
    fn drop_queued_and(&mut self, mesh: &Mesh, also: &[u32]) {
        let queued = std::mem::take(&mut self.queued);
        let mut vertices: Vec<u32> = queued.iter().flat_map(moved_by).copied().collect();
        vertices.extend_from_slice(also);
        if queued
            .iter()
            .any(|q| matches!(q.call, RunCall::Step { .. }))
        {
            vertices.extend_from_slice(&self.steps_taken);
        }
        if vertices.is_empty() {
            return;
        }
        vertices.sort_unstable();
        vertices.dedup();
        self.uploads.dropped_ahead += queued.iter().filter(|s| s.ahead.is_some()).count();
        if let Some(hashed) = self.resident.as_mut().and_then(|r| r.hashed.as_mut()) {
            // Filed where the dropped calls put them.
            hashed.gpu_drift = None;
        }
        put_back_rows(&self.gpu, self.resident.as_ref(), mesh, &vertices);
    }

    /// After the pipeline reported a step's moves: when they are not what the passes ran ahead
    /// left (the exact backstop undid some), the calls queued after were recorded on the
    /// wrong positions and are dropped, and the step's own rows go back to the mesh's: a run
    /// recomputed the normals around its moves (`moved_normals`) and filed them where the GPU
    /// put them, and the pipeline refreshes only the normals around the vertices it moved.
    pub(super) fn check_taken(&mut self, mesh: &Mesh) {
        let Some((vertices, finals)) = self.taken.take() else {
            return;
        };
        let positions = mesh.positions();
        let as_predicted = vertices
            .iter()
            .zip(&finals)
            .all(|(&v, &p)| positions[v as usize] == p);
        if !as_predicted {
            self.drop_queued_and(mesh, &vertices);
        }
    }
}

/// How a run is recorded: `count` calls, each over `guess` slots of the selection list, their
/// passes sized by `ahead` (`filter`: with the backstop filter).
struct RunShape {
    count: usize,
    guess: usize,
    ahead: AheadBounds,
    filter: bool,
}

impl RunShape {
    /// The bytes of a call's head of the selection list.
    fn list_bytes(&self) -> u64 {
        (self.guess * std::mem::size_of::<SelectedVertex>()) as u64
    }

    /// The bytes of a call's moving list.
    fn moving_bytes(&self) -> u64 {
        (self.guess * std::mem::size_of::<MovingVertex>()) as u64
    }
}

/// The edges as the calls of a run before call `j` may have lengthened them, from the
/// pipeline's bound `max_edge` at its start and the `assumed_move` of each (checked by the
/// gate, and by the host when the pipeline reaches it).
fn edge_bound(max_edge: f32, assumed_move: f32, j: usize) -> f32 {
    max_edge + EDGE_GROWTH_AHEAD * j as f32 * assumed_move
}

/// Records a run's `calls` (see [`GpuKernels::gpu_run_ahead`]) in one submission — the
/// overlay table rebuilt from its slots first, the gate started, each call's results copied
/// aside — submits it and maps them all. Returns the bytes, each call's layout, and the stride
/// between calls.
fn record_run(
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
        let (dab, source) = call.dab_and_source(plan);
        let state = StrokeState {
            max_edge: edge_bound(state.max_edge, shape.ahead.assumed_move, j),
            ..*state
        };
        let recorded = record_call(
            gpu,
            &mut encoder,
            (r, step),
            &state,
            (j, call, &dab, source),
            shape,
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
    (j, call, dab, source): (usize, RunCall, &Dab, FrameSource),
    shape: &RunShape,
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
        (source, true),
        guess,
        Some(shape.ahead),
        shape.filter,
    )?;
    let normals_of = match call {
        RunCall::Start(_) => Some((step.moving.buffer(), guess)),
        // The pipeline recomputes normals after a sample's last step: every step
        // deforms on the normals from before the sample. Each step's moving list is
        // kept until then, and vacated if the run stopped at one of them: the steps
        // taken before the stop leave their normals to the pipeline.
        RunCall::Step { k, steps, .. } => {
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

/// The queue of samples recorded ahead, oldest first.
pub(super) type Queue = VecDeque<QueuedCall>;
