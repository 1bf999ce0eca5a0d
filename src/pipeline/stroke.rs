//! A stroke while it is drawn: [`StrokeInProgress`] takes samples as they arrive (one per
//! pointer event in the app, a whole stroke file in the batch), resamples them at the stroke's
//! spacing across calls, and runs Algorithm 2's per-sample loop on each: select, deform in
//! steps of at most `max_step`, collide, update the grid. [`StrokeInProgress::finish`]
//! remeshes what the stroke touched. Feeding the samples one at a time or all at once runs the
//! same samples through the same arithmetic, so the CPU backend's meshes are bit-identical.

mod let_go;
mod mirrored;
mod remeshing;
mod volume;

use std::time::Instant;

use glam::Vec3;

use self::let_go::LetGo;
use super::engine::{Pipeline, Prepared, Scratch, longest_edge_at, millis};
use super::kernels::{CallAt, Deformed, EngineVertices, FrameSource, SampleProbe, StepKernels};
use super::step::{brush_frame, longest_move, paint, select_for_mask, steps_for};
use super::{PhaseTimes, PipelineError, Remeshing, StrokeReport};
use crate::brush::{BrushKind, Dab, DabFrame, Resampler, Sample, StrokeSettings};
use crate::collide::{Stamps, StrokeState, collide_with};
use crate::geom::largest_move;
use crate::mesh::{INVALID, Mesh};

/// A stroke begun with [`Pipeline::begin_stroke`]. Dropping it without
/// [`StrokeInProgress::finish`] ends the stroke where it is, unremeshed; the pipeline stays
/// ready for the next.
pub struct StrokeInProgress<'a> {
    pipeline: &'a mut Pipeline,
    mesh: &'a mut Mesh,
    /// `None` once ended.
    active: Option<Active>,
}

/// What one [`StrokeInProgress::add_samples`] call did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SamplesReport {
    /// Samples after resampling that the call ran.
    pub samples: usize,
    pub steps: usize,
    pub moves: usize,
    pub clamped: usize,
    pub reverted: usize,
    /// Samples whose move needed more than [`MAX_STEPS_PER_SAMPLE`](super::step::MAX_STEPS_PER_SAMPLE)
    /// steps: each moved only that many steps' worth.
    pub capped_samples: usize,
    /// Steps whose collision searches within a layer were skipped, the layer being a sheet
    /// that cannot touch itself there ([`PipelineSettings::cull`](super::PipelineSettings::cull)).
    pub culled_steps: usize,
    /// Moving vertices the collision response did not search, their own neighbourhood
    /// clearing them where their layer is a sheet not clear as a whole (summed over steps).
    pub culled_vertices: usize,
    /// The stroke stopped in this call: a step stretched an edge to this length (× L), past
    /// [`PipelineSettings::max_stretch`](super::PipelineSettings::max_stretch); the samples
    /// after it were not run, nor will any later call's be.
    pub stopped_stretched: Option<f32>,
    /// Vertices whose position, normal, BRDF or mask changed in this call (ascending): what a
    /// viewer uploads again. Vertices remeshing added are among them.
    pub changed: Vec<u32>,
    /// Remeshing between samples rewrote faces ([`Remeshing::AfterSample`], or a grab that
    /// stretched the surface): the index buffer must be sent again.
    pub topology_changed: bool,
    pub phases: PhaseTimes,
}

/// The state of a stroke between calls.
struct Active {
    stroke: StrokeSettings,
    resampler: Resampler,
    prepared: Prepared,
    scratch: Scratch,
    /// Per layer: whether the stroke moves it.
    active: Vec<bool>,
    /// Search through the grid on all cores; the reference pipeline scans on one thread.
    fast: bool,
    /// Skip the collision searches that cannot find anything ([`PipelineSettings::cull`]).
    cull: bool,
    lengths: Lengths,
    /// Where the last sample was: the next one's motion starts there.
    previous: Option<Vec3>,
    /// Samples run so far (the next one's number, [`CallAt`]).
    samples_run: usize,
    /// What a grab caught at its first sample.
    captured: Option<Vec<(u32, f32)>>,
    /// What a mirrored grab's image caught at its first sample.
    captured_image: Option<Vec<(u32, f32)>>,
    /// What of it the grab has let go of: vertices collisions hold still.
    let_go: LetGo,
    /// The long edges around a grab its last remesh between samples could not split.
    left_long: remeshing::LeftLong,
    /// Per layer: whether a volume-keeping sweep holds its volume (it is closed); empty for
    /// other brushes.
    closed_layers: Vec<bool>,
    touched_list: Vec<u32>,
    /// Vertices remeshing changed during the stroke, and the edge bound when it began: at
    /// its end the bound is brought back to what the stroke left ([`Active::tighten_edge_bound`]).
    remeshed: Vec<u32>,
    edge_bound_at_start: f32,
    /// Splits the stroke's remeshing may still make (each creates up to two faces:
    /// [`PipelineSettings::new_faces_per_stroke`]).
    splits_left: usize,
    /// A step stretched an edge past [`Lengths::stretch_limit`]: to this length (× L). The
    /// stroke runs nothing more.
    stopped_stretched: Option<f32>,
    report: StrokeReport,
}

/// The stroke's lengths in world units.
#[derive(Clone, Copy)]
struct Lengths {
    edge: f32,
    collision_distance: f32,
    step_limit: f32,
    /// [`PipelineSettings::max_stretch`] edge lengths, or the mesh's longest edge when the
    /// stroke began where that is more.
    stretch_limit: f32,
}

/// The start of one sample: what it selected and where the brush frame is.
struct Opened {
    probe: Dab,
    selection: Vec<(u32, f32)>,
    frame: DabFrame,
    targets: Option<Vec<Vec3>>,
}

impl<'a> StrokeInProgress<'a> {
    pub(super) fn begin(
        pipeline: &'a mut Pipeline,
        mesh: &'a mut Mesh,
        stroke: StrokeSettings,
    ) -> Result<StrokeInProgress<'a>, PipelineError> {
        Pipeline::check_stroke(mesh, &stroke)?;
        let (prepared, phases) = pipeline.take_prepared(mesh)?;
        let edge_bound_at_start = prepared.max_edge;
        let edge = pipeline.edge_length.unwrap_or(1.0);
        // Sized for `mesh` by `take_prepared`.
        let scratch = std::mem::take(&mut pipeline.scratch);
        let mut active = vec![false; mesh.layer_count()];
        for &l in &stroke.layers {
            active[l as usize] = true;
        }
        // A new stroke: nothing given to the kernels yet.
        pipeline.kernels.given(mesh, 0, &[]);
        let closed_layers = match stroke.brush.kind {
            BrushKind::SweepVolume => volume::closed_layers(mesh),
            _ => Vec::new(),
        };
        let (settings, fast) = (pipeline.settings, !pipeline.reference);
        let new_faces = settings.new_faces_bound(mesh.live_face_count());
        Ok(StrokeInProgress {
            pipeline,
            mesh,
            active: Some(Active {
                resampler: Resampler::with_limit(
                    stroke.resampling_step(),
                    settings.max_dabs_per_stroke,
                ),
                stroke,
                prepared,
                scratch,
                active,
                fast,
                cull: settings.cull,
                lengths: Lengths {
                    edge,
                    collision_distance: settings.collision_distance * edge,
                    step_limit: settings.max_step * edge,
                    stretch_limit: (settings.max_stretch * edge).max(edge_bound_at_start),
                },
                previous: None,
                samples_run: 0,
                captured: None,
                captured_image: None,
                let_go: LetGo::default(),
                left_long: remeshing::LeftLong::default(),
                closed_layers,
                touched_list: Vec::new(),
                remeshed: Vec::new(),
                edge_bound_at_start,
                splits_left: new_faces / 2,
                stopped_stretched: None,
                report: StrokeReport {
                    phases,
                    new_faces_bound: new_faces,
                    ..StrokeReport::default()
                },
            }),
        })
    }

    /// The mesh as the stroke has left it so far.
    pub fn mesh(&self) -> &Mesh {
        self.mesh
    }

    /// [`Pipeline::vertex_buffers`] for the mesh as the samples so far left it.
    pub fn vertex_buffers(&mut self) -> Option<EngineVertices> {
        self.pipeline.vertex_buffers(self.mesh)
    }

    /// Runs every sample `samples` completes at the stroke's spacing (the last one given is
    /// held until the next call or [`StrokeInProgress::finish`] shows where the stroke goes).
    /// Returns when their moves are in the mesh: nothing is left running for later calls.
    /// Samples that would take the stroke past `PipelineSettings::max_dabs_per_stroke` are
    /// refused, all of the call's, before any runs ([`PipelineError::TooManyDabs`]): the mesh
    /// and the stroke stay as they were, and the stroke may go on.
    pub fn add_samples(&mut self, samples: &[Sample]) -> Result<SamplesReport, PipelineError> {
        let active = self.active.as_mut().ok_or(PipelineError::StrokeEnded)?;
        let resampled = active.resample(samples)?;
        Ok(self.run_samples(&resampled))
    }

    /// Ends the stroke: runs the last sample given, remeshes what the stroke touched (as the
    /// pipeline's settings say), and reports the whole stroke.
    pub fn finish(self) -> Result<StrokeReport, PipelineError> {
        self.finish_with(&[])
    }

    /// [`StrokeInProgress::add_samples`] of the stroke's last `samples` and
    /// [`StrokeInProgress::finish`] in one call: every sample left runs in one call, the last
    /// one included (a pointer release that brings samples; the batch, which knows them all),
    /// so the GPU may record them together. The mesh is the same as with the two calls.
    pub fn finish_with(mut self, samples: &[Sample]) -> Result<StrokeReport, PipelineError> {
        let mut last = Vec::new();
        if let Some(active) = self.active.as_mut() {
            last = active.resample(samples)?;
            active.resampler.finish(&mut last);
        }
        let last_call = self.run_samples(&last);
        let mut active = self.active.take().ok_or(PipelineError::StrokeEnded)?;
        let kernels = self.pipeline.kernels.as_mut();
        kernels.given(self.mesh, active.samples_run, &[]);
        let mut remeshed =
            active.remesh_after_stroke(kernels, self.mesh, self.pipeline.settings.remeshing);
        active.fuse_after_stroke(kernels, self.mesh, &mut remeshed);
        active.tighten_edge_bound(self.mesh, &remeshed);
        let mut report = std::mem::take(&mut active.report);
        report.changed = last_call.changed;
        report.changed.extend(remeshed);
        report.changed.sort_unstable();
        report.changed.dedup();
        self.pipeline.end_stroke(self.mesh, active);
        Ok(report)
    }

    /// Runs resampled `samples`, telling the kernels of them first where they may run ahead.
    ///
    /// They run on a thread of rayon's pool, so that a step's parallel parts (a few hundred
    /// microseconds each) are split among the pool's threads from within it. Called from
    /// outside the pool, each part was handed over while the caller slept until it came back:
    /// 10–20 % of a sample on two cores.
    fn run_samples(&mut self, samples: &[Sample]) -> SamplesReport {
        rayon::scope(|_| self.run_samples_in_pool(samples))
    }

    fn run_samples_in_pool(&mut self, samples: &[Sample]) -> SamplesReport {
        let Some(active) = self.active.as_mut() else {
            return SamplesReport::default();
        };
        let pipeline = &mut *self.pipeline;
        let kernels = pipeline.kernels.as_mut();
        if active.plans_ahead(pipeline.settings.remeshing) {
            let probes = active.probes(samples);
            kernels.given(self.mesh, active.samples_run, &probes);
        }
        let mut call = SamplesReport::default();
        let remeshing = pipeline.settings.remeshing;
        let drags = active.stroke.brush.kind.drags();
        for sample in samples {
            if active.stopped_stretched.is_some() {
                break;
            }
            let Some(moved) = active.run_sample(kernels, self.mesh, sample, &mut call) else {
                continue;
            };
            if drags && remeshing != Remeshing::Off {
                active.remesh_stretched_grab(kernels, self.mesh, &moved, &mut call);
            } else if remeshing == Remeshing::AfterSample {
                active.remesh_after_sample(kernels, self.mesh, &moved, &mut call);
            }
        }
        call.changed.sort_unstable();
        call.changed.dedup();
        active.report.add_call(&call);
        call
    }
}

impl Drop for StrokeInProgress<'_> {
    fn drop(&mut self) {
        if let Some(active) = self.active.take() {
            let samples = active.samples_run;
            self.pipeline.kernels.given(self.mesh, samples, &[]);
            self.pipeline.end_stroke(self.mesh, active);
        }
    }
}

impl Pipeline {
    /// Takes back what the stroke borrowed: the grid (current with `mesh`) and the scratch.
    fn end_stroke(&mut self, mesh: &Mesh, active: Active) {
        let Active {
            mut prepared,
            mut scratch,
            touched_list,
            ..
        } = active;
        for &v in &touched_list {
            if let Some(t) = scratch.touched.get_mut(v as usize) {
                *t = false;
            }
        }
        prepared.version = mesh.version();
        self.prepared = Some(prepared);
        self.scratch = scratch;
    }
}

impl Active {
    /// The dabs `samples` complete, or an error (and the resampler as it was) when they would
    /// take the stroke past its dab bound: all of a call's samples are judged before any runs.
    fn resample(&mut self, samples: &[Sample]) -> Result<Vec<Sample>, PipelineError> {
        let mut trial = self.resampler.clone();
        let mut resampled = Vec::new();
        for &sample in samples {
            trial.push(sample, &mut resampled)?;
        }
        self.resampler = trial;
        Ok(resampled)
    }

    /// Whether the kernels may run the samples of a call ahead: each is one step that nothing
    /// else touches between — not a grab (it moves what its first sample caught) nor a sweep
    /// (both are remeshed between samples where they stretch), not with remeshing between
    /// samples, not mirrored (two dabs a step).
    fn plans_ahead(&self, remeshing: Remeshing) -> bool {
        let kind = self.stroke.brush.kind;
        kind.deforms()
            && !kind.drags()
            && remeshing != Remeshing::AfterSample
            && self.stroke.symmetry.is_none()
    }

    /// The dabs `samples` start with, as [`Active::open_sample`] will ask for them.
    fn probes(&self, samples: &[Sample]) -> Vec<SampleProbe> {
        let mut previous = self.previous;
        samples
            .iter()
            .map(|sample| {
                let probe = self.probe_at(sample, previous);
                previous = Some(sample.position);
                (probe, sample.normal)
            })
            .collect()
    }

    /// The dab a sample starts with: at the sample's position, moving from the previous
    /// sample's, its frame still to be taken from the selection.
    fn probe_at(&self, sample: &Sample, previous: Option<Vec3>) -> Dab {
        Dab {
            brush: self.stroke.brush,
            frame: DabFrame {
                center: sample.position,
                normal: Vec3::Z,
                plane_point: sample.position,
                motion: previous.map_or(Vec3::ZERO, |p| sample.position - p),
            },
            pressure: sample.pressure,
            share: 1.0,
        }
    }

    /// Whether the stroke is a grab that lets go of what collisions hold still (`let_go`):
    /// not one that should press a fuse layer onto itself, whose contact joins it.
    fn lets_go(&self) -> bool {
        self.stroke.brush.kind == BrushKind::Grab && self.stroke.fuse.is_empty()
    }

    /// At each sample, before its selection: a grab that caught something counts the
    /// vertices held still and measures the drag's turn with the brush's `motion`.
    fn start_grab_sample(&mut self, motion: Vec3) {
        if self.lets_go() && self.captured.is_some() {
            self.let_go.start_sample(motion);
        }
    }

    /// A grab's sample after its first: what it `caught`, less what it let go of (nothing,
    /// unless [`Self::lets_go`]), with the brush frame of that; `None` for other brushes.
    fn held_by_grab(
        &self,
        mesh: &Mesh,
        caught: Option<&Vec<(u32, f32)>>,
        (probe, normal): (&Dab, Option<Vec3>),
    ) -> Option<Deformed> {
        let caught = caught.filter(|_| self.stroke.brush.kind == BrushKind::Grab)?;
        let held = self.let_go.still_held(caught);
        Some(Deformed {
            frame: brush_frame(mesh, &held, probe, normal),
            selection: held,
            targets: None,
            deform_millis: 0.0,
        })
    }

    /// What a step reads that lasts for the stroke.
    fn state(&self) -> StrokeState<'_> {
        stroke_state(
            &self.prepared,
            &self.active,
            self.lengths,
            (self.fast, self.cull),
        )
    }

    /// One sample of Algorithm 2: select, paint, deform in steps, collide, update the grid,
    /// refresh the normals around what moved. Returns the vertices it moved (`None` when it
    /// deformed nothing: an empty selection, or a brush that only paints).
    fn run_sample(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &mut Mesh,
        sample: &Sample,
        call: &mut SamplesReport,
    ) -> Option<Vec<u32>> {
        let number = self.samples_run;
        self.samples_run += 1;
        call.samples += 1;
        if self.stroke.brush.kind == BrushKind::Mask {
            self.mask_sample(mesh, sample, call);
            return None;
        }
        if let Some(mirror) = self.stroke.symmetry {
            return self.run_mirrored_sample(kernels, mesh, (sample, mirror), call);
        }
        let opened = self.open_sample(kernels, mesh, sample, number, &mut call.phases);
        if opened.selection.is_empty() {
            return None;
        }
        self.paint_opened(mesh, &opened, call);
        if !self.stroke.brush.kind.deforms() {
            return None;
        }
        let moved = self.deform_in_steps(kernels, mesh, (opened, number), call);
        refresh_normals(kernels, mesh, &moved, &mut self.scratch.vertex_marks, call);
        Some(moved)
    }

    /// The mask brush: raises the mask of the vertices under the dab (and its mirror image) by
    /// the falloff weight × strength × pressure of what is left unmasked (inverted: lowers it
    /// by that share). Moves nothing.
    fn mask_sample(&mut self, mesh: &mut Mesh, sample: &Sample, call: &mut SamplesReport) {
        let started = Instant::now();
        let probe = self.probe_at(sample, self.previous);
        self.previous = Some(sample.position);
        let mut dabs = vec![probe];
        dabs.extend(
            self.stroke
                .symmetry
                .map(|m| mirrored::image_dab(&probe, &m)),
        );
        let brush = self.stroke.brush;
        let amount = brush.strength * sample.pressure;
        for dab in &dabs {
            let selection = select_for_mask(&self.state(), mesh, dab);
            let flags = mesh.flags_mut();
            for &(v, weight) in &selection {
                let flag = &mut flags[v as usize];
                let (mask, share) = (flag.mask(), (weight * amount).clamp(0.0, 1.0));
                flag.set_mask(if brush.invert {
                    mask * (1.0 - share)
                } else {
                    mask + (1.0 - mask) * share
                });
            }
            call.changed.extend(selection.iter().map(|&(v, _)| v));
        }
        call.phases.deformation += millis(started);
    }

    /// Paints the stroke's material (if it paints) under an opened dab, in the same pass as
    /// the deformation, where the brush is before it moves anything; booked under deformation.
    fn paint_opened(&self, mesh: &mut Mesh, opened: &Opened, call: &mut SamplesReport) {
        let Some(spec) = &self.stroke.paint else {
            return;
        };
        let started = Instant::now();
        let dab = Dab {
            frame: opened.frame,
            ..opened.probe
        };
        let painted = paint(&self.state(), mesh, &dab, &opened.selection, spec);
        let brdfs = mesh.brdfs_mut();
        for (&(v, _), brdf) in opened.selection.iter().zip(painted) {
            brdfs[v as usize] = brdf;
        }
        call.changed
            .extend(opened.selection.iter().map(|&(v, _)| v));
        call.phases.deformation += millis(started);
    }

    /// The sample's selection and brush frame: a grab keeps the vertices it caught at its
    /// first sample; anything else selects anew, and the kernels take the frame and the whole
    /// sample's targets with it (on the GPU in one submission, booked under selection: it
    /// cannot be split).
    fn open_sample(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &Mesh,
        sample: &Sample,
        number: usize,
        phases: &mut PhaseTimes,
    ) -> Opened {
        let started = Instant::now();
        let probe = self.probe_at(sample, self.previous);
        self.previous = Some(sample.position);
        let kind = self.stroke.brush.kind;
        self.start_grab_sample(probe.frame.motion);
        let held = self.held_by_grab(mesh, self.captured.as_ref(), (&probe, sample.normal));
        let deformed = held.unwrap_or_else(|| {
            let state = self.state();
            let source = FrameSource::Selection {
                normal: sample.normal,
            };
            let at = CallAt::Start { sample: number };
            if kind.deforms() {
                let limit = self.lengths.step_limit;
                kernels.select_deform_and_clamp(&state, mesh, &probe, (source, at), limit)
            } else {
                kernels.select_and_deform(&state, mesh, &probe, (source, false))
            }
        });
        if kind == BrushKind::Grab && self.captured.is_none() {
            self.captured = Some(deformed.selection.clone());
        }
        phases.selection += millis(started) - deformed.deform_millis;
        phases.deformation += deformed.deform_millis;
        Opened {
            probe,
            selection: deformed.selection,
            frame: deformed.frame,
            targets: deformed.targets,
        }
    }

    /// Splits the sample's motion into steps of at most `max_step` edge lengths and runs
    /// each; returns the vertices the sample moved.
    fn deform_in_steps(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &mut Mesh,
        (opened, number): (Opened, usize),
        call: &mut SamplesReport,
    ) -> Vec<u32> {
        let started = Instant::now();
        let is_grab = self.stroke.brush.kind == BrushKind::Grab;
        let whole = Dab {
            frame: opened.frame,
            ..opened.probe
        };
        let first_selection = opened.selection;
        let mut full = match opened.targets {
            Some(targets) => targets,
            None => kernels.deform(&self.state(), mesh, &whole, &first_selection, None),
        };
        let limit = self.lengths.step_limit;
        let split = steps_for(longest_move(mesh, &first_selection, &full), limit);
        let steps = split.steps;
        call.capped_samples += usize::from(split.capped);
        call.phases.deformation += millis(started);
        let mut moved_in_sample = Vec::new();
        for k in 0..steps {
            let dab = Dab {
                share: split.share,
                ..whole
            };
            let at = CallAt::Step {
                sample: number,
                k,
                steps,
            };
            // A sample taken in one step moves the selection exactly as its whole motion did
            // (same vertices, share 1): its targets are already known. Later steps select anew
            // under the dab and deform in the same call (one submission on the GPU, booked
            // under selection there).
            let started = Instant::now();
            let state = self.state();
            let (selection, targets) = if k == 0 || is_grab {
                let targets = if steps == 1 {
                    std::mem::take(&mut full)
                } else {
                    kernels.deform(&state, mesh, &dab, &first_selection, Some(at))
                };
                call.phases.deformation += millis(started);
                (first_selection.clone(), targets)
            } else {
                let source = (FrameSource::Dab, at);
                let pass = kernels.select_deform_and_clamp(&state, mesh, &dab, source, limit);
                call.phases.selection += millis(started) - pass.deform_millis;
                call.phases.deformation += pass.deform_millis;
                (pass.selection, pass.targets.unwrap_or_default())
            };
            let moved = self.take_step(kernels, mesh, (&selection, &targets), call);
            moved_in_sample.extend(moved);
            if self.stopped_stretched.is_some() {
                break;
            }
        }
        moved_in_sample
    }

    /// One step's collision phase (clamp, exact backstop) and grid update; returns the
    /// vertices it moved.
    fn take_step(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &mut Mesh,
        (selection, targets): (&[(u32, f32)], &[Vec3]),
        call: &mut SamplesReport,
    ) -> Vec<u32> {
        let started = Instant::now();
        let target_of = &mut self.scratch.target_of;
        for (i, &(v, _)) in selection.iter().enumerate() {
            target_of[v as usize] = i as u32;
        }
        let kept;
        let targets = if self.closed_layers.is_empty() {
            targets
        } else {
            let closed = &self.closed_layers;
            kept = volume::keep_volume(mesh, selection, targets, closed, target_of);
            &kept[..]
        };
        let before: Vec<Vec3> = selection
            .iter()
            .map(|&(v, _)| mesh.positions()[v as usize])
            .collect();
        let state = stroke_state(
            &self.prepared,
            &self.active,
            self.lengths,
            (self.fast, self.cull),
        );
        let moves = (selection, targets, target_of.as_slice());
        let outcome = collide_with(
            &state,
            &mut self.scratch.region,
            mesh,
            moves,
            |region, mesh, before| kernels.clamp(&state, region, mesh, moves, before),
        );
        for &(v, _) in selection {
            target_of[v as usize] = INVALID;
        }
        if self.lets_go() {
            let asked = selection.iter().zip(&before).zip(targets);
            for (((&(v, _), p), target), q) in asked.zip(&outcome.positions) {
                if p == q && p != target {
                    self.let_go.held_still(v);
                }
            }
        }
        let moved: Vec<u32> = selection
            .iter()
            .zip(&before)
            .zip(&outcome.positions)
            .filter(|((_, p), q)| p != q)
            .map(|((&(v, _), _), _)| v)
            .collect();
        let selected: Vec<u32> = selection.iter().map(|&(v, _)| v).collect();
        kernels.moved(mesh, &selected, largest_move(&before, &outcome.positions));
        let longest = longest_edge_at(mesh, &moved);
        let prepared = &mut self.prepared;
        prepared.max_edge = prepared.max_edge.max(longest);
        if longest > self.lengths.stretch_limit && self.stopped_stretched.is_none() {
            let stretched = longest / self.lengths.edge;
            self.stopped_stretched = Some(stretched);
            call.stopped_stretched = Some(stretched);
        }
        call.phases.collision += millis(started);

        let started = Instant::now();
        for &v in &moved {
            prepared.grid.move_to(v, mesh.positions()[v as usize]);
        }
        call.phases.grid_update += millis(started);

        call.steps += 1;
        call.moves += moved.len();
        call.clamped += outcome.clamped;
        call.reverted += outcome.reverted;
        call.culled_steps += usize::from(outcome.culled);
        call.culled_vertices += outcome.culled_vertices;
        for &v in &moved {
            if !self.scratch.touched[v as usize] {
                self.scratch.touched[v as usize] = true;
                self.touched_list.push(v);
            }
        }
        moved
    }
}

/// Recomputes the normals of the moved vertices and of their neighbours, whose faces also
/// turned, and tells the kernels; booked under deformation.
fn refresh_normals(
    kernels: &mut dyn StepKernels,
    mesh: &mut Mesh,
    moved: &[u32],
    marks: &mut Stamps,
    call: &mut SamplesReport,
) {
    let started = Instant::now();
    // A sample's steps may list a vertex once each.
    marks.start(mesh.vertex_count());
    let on_a_face = |v: u32| mesh.adjacency().vertex_corner[v as usize] != INVALID;
    let movers: Vec<u32> = moved
        .iter()
        .copied()
        .filter(|&v| marks.insert(v as usize) && on_a_face(v))
        .collect();
    let marks = &*marks;
    let rim = mesh.recompute_normals_around(&movers, |w| marks.contains(w as usize));
    let mut refresh = movers;
    refresh.extend(rim);
    refresh.sort_unstable();
    kernels.normals_changed(mesh, &refresh);
    call.changed.extend_from_slice(&refresh);
    call.phases.deformation += millis(started);
}

/// What a step reads that lasts for the stroke (a free function so that a step can borrow the
/// stroke's scratch beside it).
fn stroke_state<'s>(
    prepared: &'s Prepared,
    active: &'s [bool],
    lengths: Lengths,
    (fast, cull): (bool, bool),
) -> StrokeState<'s> {
    StrokeState {
        cull,
        grid: fast.then_some(&prepared.grid),
        active,
        parallel: fast,
        collision_distance: lengths.collision_distance,
        ring: prepared.ring,
        max_edge: prepared.max_edge,
    }
}
