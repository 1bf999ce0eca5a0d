//! The GPU's side of a brush step behind the pipeline's [`StepKernels`] seam: selection,
//! deformation and the proximity passes (the collision response's first phase) run as WGSL
//! kernels over a copy of the mesh that stays on the GPU. The pipeline keeps the loop, the
//! exact backstop and remeshing on the CPU, and tells the kernels what it changed.
//!
//! What stays resident, and when it is refreshed: the mesh's copy (`resident`: uploaded once
//! with room, patched with what steps and remeshing changed), the hash table (`hashed`: built
//! once, moved vertices filed in its overlay), and the per-step buffers (`step_buffers`: grown
//! when a step needs more, never reallocated otherwise).
//!
//! A step is one submission with one blocking read-back where it can be: selection and
//! deformation (`select_deform`: the selection's count, a guessed head of the list and its
//! targets together; at a sample's start also the brush frame, summed by `brush_frame` and read
//! by `deform` on the GPU), then `moving_entries` (the moving list and exclusion rings from the
//! selection list) and the whole Jacobi loop of proximity passes with the backstop's filter
//! (`clamp`: targets placed, passes sized by the GPU through indirect dispatch, final positions
//! gathered), the passes' reach sized for an assumed longest move
//! ([`AHEAD_MOVE_GROWTH`](clamp::AHEAD_MOVE_GROWTH) times the last). A step that moves
//! farther, or takes several steps, or outgrows the guessed list or the rings' room, drops
//! those passes and runs them in a second submission over the host's entries once its moves
//! are known. The proximity passes run here on hardware adapters; see [`GpuKernels::new`].
//! There, several samples of a stroke run ahead in one submission (`run_ahead`), while the
//! pipeline takes them as predicted.
//! Where a step's region is one layer and a clear sheet, the CPU's clamp would search nothing,
//! and no passes run: the host's sheet test decides (`collide::clamp_on_a_clear_sheet`), and
//! on a mesh of one layer steps recorded ahead leave their passes out while it last held.
//!
//! A GPU that fails mid-stroke (device lost, an allocation refused, a buffer past the
//! adapter's limits, a mesh past our memory budget) is not fatal: the kernels keep why and
//! finish on the CPU, and the mesh — which the CPU writes — is untouched by the failure.
//!
//! Floors: `hashed` ← `resident` ← `step_buffers` ← `clamp` ← `select_deform` ← `run_ahead`;
//! this file holds the struct, its options and the seam.

mod clamp;
mod hashed;
mod resident;
mod run_ahead;
mod run_record;
mod select_deform;
mod step_buffers;

use glam::Vec3;

pub use resident::{face_capacity, resident_bytes, vertex_capacity};

use clamp::{ClampedAhead, tally};
use hashed::TableUse;
use resident::{CopyScope, Resident};
use step_buffers::StepBuffers;

use crate::brush::Dab;
use crate::collide::{
    Backstop, Region, StepMoves, StrokeState, clamp_in_region, clamp_on_a_clear_sheet,
    lies_on_a_clear_sheet,
};
use crate::gpu::reusable::ReusableBuffer;
use crate::gpu::{AdapterSummary, GpuContext, GpuError, GpuOptions};
use crate::mesh::{Mesh, MeshVersion};
use crate::pipeline::{
    BackstopFilter, CallAt, CpuKernels, Deformed, EngineVertices, FrameSource, GpuMemory,
    SampleProbe, StepKernels, Uploads,
};

/// Selection, deformation and the proximity passes on a GPU, falling back to the CPU
/// ([`CpuKernels`]) for good once the GPU fails.
pub struct GpuKernels {
    gpu: GpuContext,
    /// Size of the last selection: how much of the list to read back with its count.
    last_selection: usize,
    /// Whether the proximity passes run on the GPU (else on the CPU, `clamp_moves`).
    proximity_on_gpu: bool,
    /// Whether, after GPU proximity passes, the backstop's first round is filtered there too
    /// (else the CPU gathers the step's region and searches it).
    backstop_on_gpu: bool,
    /// Whether a step's proximity passes may run in the submission that selected and
    /// deformed (`select_deform_and_clamp`; [`GpuOptions::clamp_in_one_submission`]).
    clamp_ahead: bool,
    /// Whether, with those, several samples of a stroke run ahead in one submission
    /// (`run_ahead`; see [`GpuKernels::set_run_ahead`]).
    run_ahead: bool,
    resident: Option<Resident>,
    step: StepBuffers,
    /// Where every submission's results are copied to be mapped.
    readback: ReusableBuffer,
    /// Set once the GPU failed: why. Everything after runs on the CPU.
    failed: Option<String>,
    /// Test hook: fail as a lost device would after this many more GPU calls.
    fail_after: Option<usize>,
    uploads: Uploads,
    filter: BackstopFilter,
    /// The proximity passes a merged submission ran ahead of the pipeline's `clamp`.
    ahead: Option<ClampedAhead>,
    /// The longest move of the last deformation read back (zero before the first).
    last_move: f32,
    /// What the host's last sheet test found (`collide::clamp_on_a_clear_sheet`): the step's
    /// region one layer and a clear sheet. While it holds on a mesh of one layer, steps are
    /// recorded ahead without their proximity passes, and each is tested before it is taken.
    /// It holds before the first test: a run recorded without passes that needed them costs
    /// a read-back more, one recorded with passes that needed none costs them (on lavapipe,
    /// the plane bench's runs took eleven times as long with them).
    expect_clear: bool,
    /// Steps taken with passes since the last sheet test: one is tested every
    /// [`SHEET_TEST_EVERY`], so that the expectation follows the stroke.
    untested_steps: usize,
    /// How much a run's later samples assume the edges grow per sample before them, as a
    /// share of the assumed move: raised by runs that measured more on this mesh
    /// (`RunShape::next_edge_growth`).
    edge_growth: f32,
    /// The step limit of the stroke, and the last sample start: the pipeline deforms its
    /// selection again at the first step of a sample of several, which then records the
    /// sample's steps and the samples after it in one run (`deform`).
    step_limit: Option<f32>,
    opened: Option<OpenedSample>,
    /// The planned sample that stopped the last run where a run starting at it would stop
    /// again: the pipeline's call for it runs alone.
    no_run_at: Option<usize>,
    /// The vertices the steps of the current sample taken from a run moved: the run
    /// recomputed their normals after the sample's last step, which go back with it.
    steps_taken: Vec<u32>,
    /// The samples the pipeline gave (`given`: those of its current call), the stroke's number
    /// of the first, and the index of the one after the last it took from a submission that
    /// ran several ahead.
    plan: Vec<SampleProbe>,
    plan_first: usize,
    plan_next: usize,
    /// Samples run ahead in such a submission, waiting for the pipeline (`run_ahead`).
    queued: run_ahead::Queue,
    /// The vertices and final positions of the last step taken from passes run ahead, to see
    /// whether the pipeline kept them (`moved`).
    taken: Option<(Vec<u32>, Vec<Vec3>)>,
    /// The sample taken last was filed in the overlay on the GPU as it ran ahead.
    taken_filed: bool,
    /// Check the GPU's filing before the host replaces it (`set_check_filing`), and what the
    /// first check found wrong.
    check_filing: bool,
    filing_error: Option<String>,
    /// Read-backs the checks made, left out of [`Uploads::read_backs`].
    check_read_backs: usize,
}

/// While no clear sheet is expected, one step in this many is tested for one (and the first of
/// each stroke): the region gathered on the CPU, which the backstop's filter on the GPU
/// otherwise spares, paid for an eighth of the steps.
const SHEET_TEST_EVERY: usize = 8;

/// A sample start the pipeline may go on to deform in several steps.
#[derive(Debug, Clone, Copy)]
struct OpenedSample {
    /// Its number in the stroke, to know the call for its first step.
    sample: usize,
    /// Where it is in the plan: the samples after it follow its steps in their run.
    planned: Option<usize>,
}

/// The kernels every stroke on the GPU runs: the hash table and its overlay, selection, brush
/// frame, deformation, normals.
const STROKE_KERNELS: &[&str] = &[
    "cell_keys",
    "cell_counts",
    "scan",
    "scan_add",
    "scatter",
    "overlay_members",
    "overlay_keys",
    "overlay_entries",
    "select",
    "brush_frame",
    "dispatch_args",
    "deform",
    "vertex_normals",
    "moved_normals",
];

/// The kernels of the proximity passes, the backstop's filter and the gate of runs ahead.
const PROXIMITY_KERNELS: &[&str] = &[
    "moving_entries",
    "proximity",
    "apply_moves",
    "backstop_filter",
    "longest_move",
    "sample_gate",
    "moved_edges",
];

impl GpuKernels {
    /// Compiles the kernels strokes will run with these options, so that wgpu's translation of
    /// them (about 80 ms in all on lavapipe) and a hardware driver's compiler run before the
    /// first stroke instead of inside it. (Lavapipe compiles machine code at the first dispatch.)
    fn compile_kernels(&self) -> Result<(), GpuError> {
        let proximity = if self.proximity_on_gpu {
            PROXIMITY_KERNELS
        } else {
            &[]
        };
        for name in STROKE_KERNELS.iter().chain(proximity) {
            self.gpu.compute_pipeline(name)?;
        }
        Ok(())
    }

    /// Kernels on `gpu` with the default [`GpuOptions`].
    pub fn new(gpu: GpuContext) -> GpuKernels {
        GpuKernels::with_options(gpu, &GpuOptions::default())
    }

    /// Kernels on `gpu`. The proximity passes run there on a hardware GPU; on a software
    /// adapter (lavapipe) they stay on the CPU unless `options` say otherwise: the kernel's
    /// broad phase walks every cell within reach of each moving vertex (reach set by the
    /// longest edge), which lavapipe runs hundreds of times slower than the CPU's per-step face
    /// grid. Runs ahead likewise.
    pub fn with_options(gpu: GpuContext, options: &GpuOptions) -> GpuKernels {
        let hardware = !gpu.adapter.software;
        GpuKernels {
            last_selection: 0,
            proximity_on_gpu: options.proximity_on_gpu.unwrap_or(hardware),
            backstop_on_gpu: options.backstop_filter_on_gpu,
            clamp_ahead: options.clamp_in_one_submission,
            run_ahead: options.runs_ahead.unwrap_or(hardware),
            step: StepBuffers::new(&gpu),
            readback: ReusableBuffer::readback("step readback"),
            gpu,
            resident: None,
            failed: None,
            fail_after: None,
            uploads: Uploads::default(),
            filter: BackstopFilter::default(),
            ahead: None,
            last_move: 0.0,
            expect_clear: true,
            untested_steps: SHEET_TEST_EVERY,
            edge_growth: run_record::EDGE_GROWTH_LEAST,
            step_limit: None,
            opened: None,
            no_run_at: None,
            steps_taken: Vec::new(),
            plan: Vec::new(),
            plan_first: 0,
            plan_next: 0,
            queued: run_ahead::Queue::new(),
            taken: None,
            taken_filed: false,
            check_filing: false,
            filing_error: None,
            check_read_backs: 0,
        }
    }

    /// The adapter the kernels run on.
    pub fn adapter(&self) -> &AdapterSummary {
        &self.gpu.adapter
    }

    /// Runs the proximity passes on the GPU (`true`) or on the CPU.
    pub fn set_proximity_on_gpu(&mut self, on: bool) {
        self.proximity_on_gpu = on;
    }

    pub fn proximity_on_gpu(&self) -> bool {
        self.proximity_on_gpu
    }

    /// With the proximity passes on the GPU, runs the samples given in one call ahead in one
    /// submission (`true`) or one submission per step ([`GpuOptions::runs_ahead`]).
    pub fn set_run_ahead(&mut self, on: bool) {
        self.run_ahead = on;
    }

    /// Before the host refiles over what the GPU filed while samples ran ahead, reads that
    /// filing back and checks it against the mesh (`Hashed::check`); the first fault is
    /// reported by `check_copy`. A validator for tests: it reads the whole filing back.
    pub fn set_check_filing(&mut self, on: bool) {
        self.check_filing = on;
    }

    /// See [`GpuKernels::set_check_filing`]: called before anything may refile.
    fn check_gpu_filing(&mut self, mesh: &Mesh) {
        let Some(h) = self.resident.as_ref().and_then(|r| r.hashed.as_ref()) else {
            return;
        };
        if self.check_filing && h.filed_on_gpu && self.filing_error.is_none() {
            let before = self.gpu.read_backs();
            self.filing_error = h.check(&self.gpu, mesh).err();
            self.check_read_backs += self.gpu.read_backs() - before;
        }
    }

    /// Makes the GPU calls after the next `calls` fail, as a lost device would: for tests of
    /// the fallback.
    pub fn fail_after(&mut self, calls: usize) {
        self.fail_after = Some(calls);
    }

    fn check_injected_failure(&mut self) -> Result<(), GpuError> {
        match &mut self.fail_after {
            Some(0) => Err(GpuError::Readback("device lost (simulated)".into())),
            Some(n) => {
                *n -= 1;
                Ok(())
            }
            None => Ok(()),
        }
    }

    /// [`StepKernels::select_deform_and_clamp`] on the GPU, falling back to the CPU: the call a
    /// run queued, else at the start of a given sample a run of the given samples from it,
    /// else one submission for this step.
    fn select_deform_and_clamp_on_gpu(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        (source, at): (FrameSource, CallAt),
        step_limit: f32,
    ) -> Deformed {
        let how = (source, true);
        self.taken_filed = false;
        let taken = match at {
            CallAt::Start { sample } => {
                let planned = self.plan_index(sample);
                self.take_queued_start(mesh, planned, state.max_edge)
                    .or_else(|| {
                        let from = planned.filter(|&at| self.may_start_run(at))?;
                        let run = (None, Some(from));
                        self.on_gpu(|k| k.gpu_run_ahead(state, mesh, run, step_limit))?;
                        self.take_queued_start(mesh, planned, state.max_edge)
                    })
            }
            CallAt::Step { .. } => self.take_queued_step(mesh, (at, None), state.max_edge),
        };
        if let Some(deformed) = taken {
            return deformed;
        }
        self.on_gpu(|k| k.gpu_select_and_deform(state, mesh, dab, how, Some(step_limit)))
            .unwrap_or_else(|| CpuKernels.select_and_deform(state, mesh, dab, how))
    }

    /// Whether steps recorded ahead on `mesh` now leave out their passes: the last sheet test
    /// found a clear sheet alone, the stroke culls, and the mesh has one layer. Among several,
    /// a region of one layer alone and clear lasts a step or two: at 600 faces, 16 strokes,
    /// plaster, bark and metal each had one step recorded ahead without passes that needed
    /// them, and none that did not, and their strokes read back 10-13 % more for it. There
    /// steps ahead keep their passes, and only steps whose passes run apart are tested.
    fn skips_passes(&self, state: &StrokeState<'_>, mesh: &Mesh) -> bool {
        self.expect_clear && state.cull && mesh.layer_count() == 1
    }

    /// Whether a step whose passes are still to run is one to test for a clear sheet alone:
    /// every one while such a sheet is expected, else one in [`SHEET_TEST_EVERY`].
    fn sheet_test_due(&mut self) -> bool {
        self.untested_steps += 1;
        self.expect_clear || self.untested_steps >= SHEET_TEST_EVERY
    }

    /// The first phase of a step where its region is one layer and a clear sheet at the
    /// targets (`collide::clamp_on_a_clear_sheet`), skipping the passes there; remembers
    /// what it found for the steps after it.
    fn sheet_test(
        &mut self,
        state: &StrokeState<'_>,
        region: &mut Region,
        mesh: &mut Mesh,
        moves: StepMoves<'_>,
        before: &[Vec3],
    ) -> bool {
        self.untested_steps = 0;
        self.expect_clear = clamp_on_a_clear_sheet(state, region, mesh, moves, before);
        self.uploads.skipped_passes += usize::from(self.expect_clear);
        self.expect_clear
    }

    /// Takes the passes run ahead for exactly the pipeline's moves: their final positions into
    /// `mesh`, and what they left the backstop; on a mesh of one layer, every
    /// [`SHEET_TEST_EVERY`] steps a sheet test where they left the selection
    /// (`collide::lies_on_a_clear_sheet`), a guide for the steps after it.
    fn take_ahead(
        &mut self,
        state: &StrokeState<'_>,
        region: &mut Region,
        mesh: &mut Mesh,
        (selection, ahead): (&[(u32, f32)], ClampedAhead),
    ) -> Backstop {
        self.uploads.clamped_ahead += 1;
        tally(&mut self.filter, &ahead.backstop, self.backstop_on_gpu);
        let positions = mesh.positions_mut();
        for (&v, &p) in ahead.vertices.iter().zip(&ahead.finals) {
            positions[v as usize] = p;
        }
        if mesh.layer_count() == 1 && self.sheet_test_due() {
            self.untested_steps = 0;
            let moved = (selection, ahead.targets.as_slice());
            self.expect_clear = lies_on_a_clear_sheet(state, region, mesh, moved);
        }
        self.taken = Some((ahead.vertices, ahead.finals));
        ahead.backstop
    }

    /// A step's first phase in a submission of its own, its moves known: the passes on the GPU
    /// where they run there and it has not failed, else on the CPU (`clamp_in_region`).
    fn clamp_apart(
        &mut self,
        state: &StrokeState<'_>,
        region: &mut Region,
        mesh: &mut Mesh,
        moves: StepMoves<'_>,
        before: &[Vec3],
    ) -> Backstop {
        let (selection, targets, _) = moves;
        if self.proximity_on_gpu
            && let Some((finals, backstop)) =
                self.on_gpu(|k| k.gpu_clamp(state, mesh, selection, targets, before))
        {
            let positions = mesh.positions_mut();
            for (&(v, _), p) in selection.iter().zip(finals) {
                positions[v as usize] = p;
            }
            return backstop;
        }
        clamp_in_region(state, region, mesh, moves, before)
    }

    /// `run`'s result, unless the GPU was given up before or fails now (then given up for
    /// good): the caller falls back to the CPU on `None`.
    fn on_gpu<T>(&mut self, run: impl FnOnce(&mut GpuKernels) -> Result<T, GpuError>) -> Option<T> {
        if self.failed.is_some() {
            return None;
        }
        run(self).map_err(|error| self.give_up(error)).ok()
    }

    /// Gives the GPU up for good, keeping why (the pipeline reports it).
    fn give_up(&mut self, error: GpuError) {
        self.failed = Some(error.to_string());
        self.resident = None;
    }
}

impl StepKernels for GpuKernels {
    fn name(&self) -> String {
        self.gpu.adapter.name.clone()
    }

    fn collides_on_gpu(&self) -> bool {
        self.proximity_on_gpu && self.failed.is_none()
    }

    fn failure(&self) -> Option<String> {
        self.failed.clone()
    }

    fn warm_up(&mut self, mesh: &Mesh, cell_size: f32) {
        // A stroke's first step is tested for a clear sheet: the last stroke's may be elsewhere.
        self.untested_steps = SHEET_TEST_EVERY;
        // Not counted as a GPU call by the `fail_after` hook: the tests of the fallback aim
        // their failures at the strokes' calls.
        self.on_gpu(|k| {
            // With no copy of a mesh yet: once, not before every stroke.
            if k.resident.is_none() {
                k.compile_kernels()?;
            }
            let tables = (&mut k.resident, &mut k.uploads);
            GpuKernels::prepare(&k.gpu, tables, mesh, cell_size, TableUse::Present)?;
            // Done here, not in the first call that reads something back.
            k.gpu.wait()
        });
    }

    fn select(&mut self, state: &StrokeState<'_>, mesh: &Mesh, dab: &Dab) -> Vec<(u32, f32)> {
        // The selection alone: the same submission as with a deformation, less its passes.
        let alone = (FrameSource::Dab, false);
        self.on_gpu(|k| k.gpu_select_and_deform(state, mesh, dab, alone, None))
            .map(|selected| selected.selection)
            .unwrap_or_else(|| CpuKernels.select(state, mesh, dab))
    }

    fn select_and_deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        how: (FrameSource, bool),
    ) -> Deformed {
        self.on_gpu(|k| k.gpu_select_and_deform(state, mesh, dab, how, None))
            .unwrap_or_else(|| CpuKernels.select_and_deform(state, mesh, dab, how))
    }

    fn select_deform_and_clamp(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        (source, at): (FrameSource, CallAt),
        step_limit: f32,
    ) -> Deformed {
        let deformed =
            self.select_deform_and_clamp_on_gpu(state, mesh, dab, (source, at), step_limit);
        self.step_limit = Some(step_limit);
        if let CallAt::Start { sample } = at {
            self.steps_taken.clear();
            self.opened = Some(OpenedSample {
                sample,
                planned: self.plan_index(sample),
            });
        }
        deformed
    }

    fn given(&mut self, mesh: &Mesh, first: usize, probes: &[SampleProbe]) {
        self.drop_queued(mesh);
        self.plan = probes.to_vec();
        self.plan_first = first;
        self.plan_next = 0;
        self.opened = None;
        self.no_run_at = None;
        self.steps_taken.clear();
    }

    fn deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        selection: &[(u32, f32)],
        at: Option<CallAt>,
    ) -> Vec<Vec3> {
        // The first step of a sample of several: the selection its start found, under the same
        // brush (a share of the move). A run may have recorded it after the start (a split
        // step); else its steps and the samples after it run ahead in one submission; or, when
        // they do not, the step is selected again with the deformation and its passes in one
        // submission, as a later step is, when the selection comes out the same.
        let opened = self.opened.take();
        let first_step = match (opened, at) {
            (
                Some(o),
                Some(CallAt::Step {
                    sample,
                    k: 0,
                    steps,
                }),
            ) if o.sample == sample => Some((o, steps)),
            _ => None,
        };
        if let (Some((opened, steps)), Some(limit)) = (first_step, self.step_limit)
            && self.failed.is_none()
        {
            let first = CallAt::Step {
                sample: opened.sample,
                k: 0,
                steps,
            };
            let queued = self.take_queued_step(mesh, (first, Some(selection)), state.max_edge);
            if let Some(Deformed {
                targets: Some(targets),
                ..
            }) = queued
            {
                return targets;
            }
            let sample = (opened.sample, steps);
            if let Some(targets) = self.run_steps_ahead(
                state,
                mesh,
                (dab, selection),
                (sample, opened.planned),
                limit,
            ) {
                return targets;
            }
            let how = (FrameSource::Dab, true);
            if let Some(Deformed {
                selection: found,
                targets: Some(targets),
                ..
            }) = self.on_gpu(|k| k.gpu_select_and_deform(state, mesh, dab, how, Some(limit)))
                && found == selection
            {
                return targets;
            }
        }
        self.on_gpu(|k| k.gpu_deform(state, mesh, dab, selection))
            .unwrap_or_else(|| CpuKernels.deform(state, mesh, dab, selection, at))
    }

    fn clamp(
        &mut self,
        state: &StrokeState<'_>,
        region: &mut Region,
        mesh: &mut Mesh,
        moves: StepMoves<'_>,
        before: &[Vec3],
    ) -> Backstop {
        let (selection, targets, _) = moves;
        let same = self.ahead.as_ref().is_some_and(|ahead| {
            ahead.targets.as_slice() == targets
                && selection
                    .iter()
                    .map(|&(v, _)| v)
                    .eq(ahead.vertices.iter().copied())
        });
        match self.ahead.take() {
            Some(ahead) if same && !ahead.without_passes => {
                return self.take_ahead(state, region, mesh, (selection, ahead));
            }
            // Recorded without passes: right where the region is a clear sheet alone; else
            // dropped, with the samples queued after it, and its passes run apart.
            Some(ahead) if same => {
                if self.sheet_test(state, region, mesh, moves, before) {
                    self.uploads.clamped_ahead += 1;
                    self.taken = Some((ahead.vertices, ahead.finals));
                    return Backstop::Search;
                }
                self.uploads.passes_needed += 1;
                self.ahead = Some(ahead);
                self.drop_ahead(mesh);
                return self.clamp_apart(state, region, mesh, moves, before);
            }
            // Passes run ahead for other moves: dropped, with the samples queued after them.
            not_these => {
                self.ahead = not_these;
                self.drop_ahead(mesh);
            }
        }
        if self.proximity_on_gpu
            && self.failed.is_none()
            && self.sheet_test_due()
            && self.sheet_test(state, region, mesh, moves, before)
        {
            return Backstop::Search;
        }
        self.clamp_apart(state, region, mesh, moves, before)
    }

    fn moved(&mut self, mesh: &Mesh, vertices: &[u32], max_move: f32) {
        self.drop_ahead(mesh);
        self.check_taken(mesh);
        if self.failed.is_none() {
            self.gpu_moved(mesh, vertices, max_move);
        }
    }

    fn normals_changed(&mut self, mesh: &Mesh, vertices: &[u32]) {
        if self.failed.is_none() {
            self.gpu_normals_changed(mesh, vertices);
        }
    }

    fn remeshed(&mut self, mesh: &Mesh, since: MeshVersion, changed: &[u32]) {
        self.drop_all_ahead(mesh);
        if self.failed.is_none() {
            self.gpu_remeshed(mesh, since, changed);
        }
    }

    fn uploads(&self) -> Option<Uploads> {
        let (submit_micros, waited_micros) = self.gpu.host_micros();
        Some(Uploads {
            submissions: self.gpu.submissions(),
            submit_micros,
            waited_micros,
            read_backs: self.gpu.read_backs() - self.check_read_backs,
            ..self.uploads
        })
    }

    fn backstop_filter(&self) -> Option<BackstopFilter> {
        (self.proximity_on_gpu && self.backstop_on_gpu).then_some(self.filter)
    }

    fn gpu_memory(&self, mesh: &Mesh) -> Option<GpuMemory> {
        self.resident.as_ref()?;
        let report = self.gpu.device.generate_allocator_report();
        Some(GpuMemory {
            allocated_bytes: report.as_ref().map(|r| r.total_allocated_bytes),
            reserved_bytes: report.as_ref().map(|r| r.total_reserved_bytes),
            budget_bytes: resident_bytes(mesh),
            budget_limit_bytes: self.gpu.budget_bytes,
        })
    }

    fn forget_mesh(&mut self) {
        self.resident = None;
        // Sized for the last mesh's brushes.
        self.last_selection = 0;
        self.last_move = 0.0;
        self.edge_growth = run_record::EDGE_GROWTH_LEAST;
    }

    fn vertex_buffers(&mut self, mesh: &Mesh) -> Option<EngineVertices> {
        self.on_gpu(|k| {
            let tables = (&mut k.resident, &mut k.uploads);
            let r = GpuKernels::sync(&k.gpu, tables, mesh, CopyScope::Geometry)?;
            Ok(EngineVertices {
                positions: r.vertices.positions.clone(),
                normals: r.normals.clone(),
                count: r.vertices.count,
            })
        })
    }

    fn check_copy(&self, mesh: &Mesh) -> Result<(), String> {
        if let Some(error) = &self.filing_error {
            return Err(format!("the GPU's filing of samples run ahead: {error}"));
        }
        match &self.resident {
            Some(r) if r.version == mesh.version() => r.check(&self.gpu, mesh),
            Some(_) => Err("the GPU copy is behind the mesh".into()),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{PROXIMITY_KERNELS, STROKE_KERNELS};

    #[test]
    fn the_warm_up_compiles_every_kernel_once() {
        let mut listed: Vec<&str> = STROKE_KERNELS
            .iter()
            .chain(PROXIMITY_KERNELS)
            .copied()
            .collect();
        listed.sort_unstable();
        let mut kernels: Vec<&str> = crate::gpu::shaders::KERNELS
            .iter()
            .map(|&(name, _)| name)
            .collect();
        kernels.sort_unstable();
        assert_eq!(listed, kernels);
    }
}
