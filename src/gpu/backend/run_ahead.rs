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
//! step count is known only from its whole move. Where a sample's settings do not rule that
//! out, the run records after its start the two steps of a move over the step limit by at most
//! twice ([`RunCall::SplitStep`]: under half the move, the frame read from the sums the start
//! left): the gate lets such a start defer its move to them — it moves nothing, they run — and
//! empties them otherwise. Any other sample of several steps stops the run at its start; what
//! that start read (its selection, frame and whole move: nothing moved since) answers the
//! pipeline's call for it, and the pipeline's call for its first step records its steps and the
//! samples after it in the next run ([`RunCall::Step`]). Each step deforms on the normals from
//! before the sample, as the pipeline's do; the normals its moves turned are recomputed after
//! its last step.
//!
//! [`StepKernels::given`]: crate::pipeline::StepKernels::given

use std::collections::VecDeque;

use glam::Vec3;

use super::GpuKernels;
use super::clamp::ClampedAhead;
use super::hashed::{TableUse, cell_size};
use super::resident::put_back_rows;
use super::run_record::{RunCall, RunShape, SPLIT_STEPS, may_take_steps, record_run};
use super::select_deform::{AheadBounds, SampleLayout, in_vertex_order, permuted, selection_guess};
use crate::brush::{Dab, DabFrame};
use crate::collide::{Backstop, StrokeState};
use crate::gpu::{GateSplit, GateStatus, GpuError, MovingVertex, SelectedVertex, ring_bytes};
use crate::mesh::Mesh;
use crate::pipeline::step::longest_move;
use crate::pipeline::{CallAt, Deformed};

/// At most this many samples in one submission: the read-back grows with each, and each later
/// sample's passes are sized for edges grown by a share of the move per sample before it
/// ([`RunShape::edge_bound`]), so their reach grows with the run. A run records every sample
/// given from where it starts, up to this many: a stroke given whole costs one blocking
/// read-back per run, one more per gate stop. A run the gate stops still has the GPU go
/// through the recorded passes of every sample after the stop, emptied but dispatched (a
/// fixed cost per dispatch on a hardware GPU); runs that started at two samples and doubled
/// spent fewer such dispatches but read back 4 times where this reads back once or twice
/// (`docs/gpu.md`).
pub(super) const MAX_SAMPLES_AHEAD: usize = 32;

/// A sample of at most this many steps has them recorded in a run (each step's moving list
/// is kept until the sample's last, for the normals): the bench strokes took at most 3.
pub(super) const MAX_STEPS_AHEAD: usize = 8;

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

impl QueuedCall {
    /// A start whose run did not make its move (the gate stopped the run there, or the start
    /// deferred its move to its split steps): its selection and whole move hold, since nothing
    /// moved, and answer the pipeline's call for it; it filed nothing.
    fn answered_with(mut self, targets: Vec<Vec3>) -> Self {
        self.deformed.targets = Some(targets);
        self.filed = false;
        self
    }
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

    /// Whether a run may start at planned sample `at`: runs ahead on, not the last of the plan
    /// (a run of one sample is a single step), not one a run reached already (its queued start
    /// was dropped for moving farther than assumed), nor one that stopped a run where the next
    /// would stop too ([`GpuKernels::after_stop`]).
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
    /// given, then the given samples from `from` (at most [`MAX_SAMPLES_AHEAD`]), and queues
    /// what each left for the pipeline; nothing when that is fewer than two. The passes are
    /// sized as a single step's would be (`assumed_move`: a multiple of the last move, within
    /// `limit`; a split step's for the limit), each later call's from edges grown by a share
    /// of that move per call before it ([`RunShape::edge_bound`]).
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
        let (calls, held_lists) = self.run_calls(steps, from, limit);
        let count = calls.len();
        let filter = self.backstop_on_gpu;
        let assumed_move = self.assumed_move(limit);
        let skip_passes = self.skips_passes(state, mesh);
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
        if count < 2 || ring_bytes(guess) > binding || held_lists as u64 * moving_bytes > binding {
            return Ok(());
        }
        step.reserve_sample(gpu, (r, mesh), guess, true, true, filter)?;
        step.held_moving
            .reserve(gpu, held_lists as u64 * moving_bytes)?;
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
                split: GateSplit::default(),
                skip_passes,
            },
            filter,
            limit,
            edge_growth: self.edge_growth,
        };
        let run = (calls.as_slice(), self.plan.as_slice());
        let (data, layouts, stride) = record_run(gpu, (&*r, step, readback), state, run, &shape)?;
        self.uploads.batches += 1;
        let read = (data.as_slice(), layouts.as_slice(), stride);
        self.queue_run(read, &calls, state.max_edge, &shape, capacity);
        Ok(())
    }

    /// The calls of a run: the `steps` of a sample of several when given, then the given
    /// samples from `from` (at most [`MAX_SAMPLES_AHEAD`]), each followed by its split steps
    /// where its move may be over the step `limit`; and how many moving lists the steps of
    /// one sample keep at most.
    fn run_calls(
        &self,
        steps: Option<(usize, Dab, usize)>,
        from: Option<usize>,
        limit: f32,
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
        let mut held_lists = calls.len();
        if let Some(from) = from {
            let samples = (self.plan.len() - from).min(MAX_SAMPLES_AHEAD);
            for index in from..from + samples {
                calls.push(RunCall::Start(index));
                if may_take_steps(&self.plan[index].0, limit) {
                    calls.extend((0..SPLIT_STEPS).map(|k| RunCall::SplitStep { index, k }));
                    held_lists = held_lists.max(SPLIT_STEPS);
                }
            }
        }
        (calls, held_lists)
    }

    /// Queues what each of a run's `calls` left for the pipeline — `data`, `stride` bytes a
    /// call, split as `layouts` — up to the call where the gate stopped the run (that one too
    /// when the pipeline's call for it is answered from here, [`GpuKernels::after_stop`]), and
    /// notes what the GPU filed for the host's next filing. `max_edge`: the pipeline's bound
    /// on the edges at the run's start; `capacity`: the selection list's. A start that
    /// deferred its move is answered as a stopped one is, and its split steps are queued as
    /// the steps the pipeline will ask for; the split steps of one that did not moved nothing.
    fn queue_run(
        &mut self,
        (data, layouts, stride): (&[u8], &[SampleLayout], u64),
        calls: &[RunCall],
        max_edge: f32,
        shape: &RunShape,
        capacity: usize,
    ) {
        let count = shape.count;
        // What the GPU filed, for the host's next filing to hold too.
        let mut filed_on_gpu = Vec::new();
        // The frame of the last start, when it deferred its move to its split steps.
        let mut deferred: Option<DabFrame> = None;
        // The last call read and the gate's bound on the edges before it.
        let mut last_edge = None;
        for (j, bytes) in data.chunks_exact(stride as usize).enumerate() {
            let mut call = calls[j];
            let (mut dab, _) = call.dab_and_frame(&self.plan);
            if let RunCall::SplitStep { index, k } = call {
                let Some(frame) = deferred else {
                    continue;
                };
                dab.frame = frame;
                call = RunCall::Step {
                    sample: self.plan_first + index,
                    dab,
                    k,
                    steps: SPLIT_STEPS,
                };
            }
            let read = self.read_call(bytes, (layouts[j], &dab), shape.guess, capacity);
            let assumed_move = call.assumed_move(shape.ahead.assumed_move, shape.limit);
            let mut queued = QueuedCall {
                call,
                deformed: Deformed {
                    targets: None,
                    selection: read.selection,
                    frame: read.frame,
                    deform_millis: 0.0,
                },
                ahead: None,
                assumed_move,
                max_edge: shape.edge_bound(max_edge, (calls, j)),
                filed: j + 1 < count,
            };
            let status = read.status;
            last_edge = Some((j, status.edge_bound()));
            let is_start = matches!(call, RunCall::Start(_));
            let defers = is_start && status.stopped == 0 && status.deferred != 0;
            if is_start {
                deferred = defers.then_some(read.frame);
            }
            if status.stopped != 0 {
                // The gate stopped the run here, before this call moved anything, and the
                // calls after it selected nothing: there is nothing to put back.
                let longest = status.longest_move();
                self.uploads
                    .count_gate_stop(status.stopped, longest, shape.limit);
                if let RunCall::Start(index) = call
                    && self.after_stop(index, status, shape.limit)
                {
                    // Its steps are recorded when the pipeline asks for the first.
                    self.queued.push_back(queued.answered_with(read.targets));
                }
                break;
            }
            if defers {
                // Its move went to its split steps, which follow.
                self.uploads.split_ahead += 1;
                self.queued.push_back(queued.answered_with(read.targets));
                continue;
            }
            if j + 1 < count {
                filed_on_gpu.extend(queued.deformed.selection.iter().map(|&(v, _)| v));
            }
            if let Some((finals, backstop)) = read.clamped {
                queued.deformed.targets = Some(read.targets.clone());
                queued.ahead = Some(ClampedAhead {
                    vertices: queued.deformed.selection.iter().map(|&(v, _)| v).collect(),
                    targets: read.targets,
                    finals,
                    backstop,
                    without_passes: layouts[j].clamp.is_some_and(|c| c.without_passes),
                });
            }
            self.queued.push_back(queued);
        }
        if let Some(hashed) = self.resident.as_mut().and_then(|r| r.hashed.as_mut()) {
            hashed.moved.extend_from_slice(&filed_on_gpu);
        }
        if let Some((j, edge)) = last_edge {
            self.edge_growth = shape.next_edge_growth((max_edge, edge), (calls, j));
        }
    }

    /// What one call of a run left, `bytes` from its count on, laid out as `layout` under
    /// `dab`; `guess`: the slots of the list its passes ran over, `capacity`: the list's.
    fn read_call(
        &mut self,
        bytes: &[u8],
        (layout, dab): (SampleLayout, &Dab),
        guess: usize,
        capacity: usize,
    ) -> CallRead {
        let found =
            (u32::from_le_bytes(bytes[..4].try_into().expect("four bytes")) as usize).min(capacity);
        self.last_selection = self.last_selection.max(found);
        let list_bytes = guess * std::mem::size_of::<SelectedVertex>();
        let list: Vec<SelectedVertex> =
            bytemuck::pod_collect_to_vec(&bytes[4..4 + 8 * found.min(guess)]);
        let parts = layout.split(&bytes[4 + list_bytes..], dab);
        let status = parts.gate.expect("runs go through the gate");
        let (order, selection) = in_vertex_order(&list);
        let targets = permuted(
            &order,
            &bytemuck::pod_collect_to_vec(&parts.targets[..list.len() * 12]),
        );
        // The gate stops a run on a cut list or cut rings (the same count and buffer).
        debug_assert!(status.stopped != 0 || (found <= guess && parts.ring_overflows == Some(0)));
        let clamped = (status.stopped == 0 && !selection.is_empty()).then(|| {
            let clamp = layout.clamp.expect("passes recorded");
            let (finals, backstop) = self.step.parse_clamp(parts.clamp, guess, clamp);
            (permuted(&order, &finals), backstop)
        });
        CallRead {
            selection,
            frame: parts.frame,
            targets,
            status,
            clamped,
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
            // Split steps are queued as the steps they turned out to be.
            RunCall::Start(_) | RunCall::SplitStep { .. } => false,
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
            RunCall::Step { .. } | RunCall::SplitStep { .. } => {
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

/// What one call of a run read back, in vertex order: its selection, frame and targets, the
/// gate's verdict, and where its passes ran the moves' final positions and the backstop's.
struct CallRead {
    selection: Vec<(u32, f32)>,
    frame: DabFrame,
    targets: Vec<Vec3>,
    status: GateStatus,
    clamped: Option<(Vec<Vec3>, Backstop)>,
}

/// The queue of samples recorded ahead, oldest first.
pub(super) type Queue = VecDeque<QueuedCall>;
