//! The CPU backend: Algorithm 2 on all cores, and the same code single-threaded with brute-force
//! search as the reference it is tested against.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::kernels::{CpuKernels, Deformed, FrameSource, SampleProbe, StepKernels};
use super::step::{Region, StrokeState, brush_frame, collide_with, longest_move, paint, steps_for};
use super::{
    BackstopFilter, GpuMemory, PhaseTimes, PipelineError, PipelineSettings, Remeshing,
    SculptPipeline, StrokeHook, StrokeReport, Uploads,
};
use crate::brush::{BrushKind, Dab, DabFrame, Sample, Stroke, resample};
use crate::collide::neighbourhood::exclusion_ring;
use crate::geom::largest_move;
use crate::grid::SpatialHash;
use crate::mesh::{INVALID, Mesh, MeshVersion};
use crate::remesh::{RemeshReport, RemeshSettings, remesh_region};

/// How nearby elements are found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Search {
    /// Through the spatial hash and a per-step face grid.
    Grid,
    /// By scanning every vertex and face: slow, obviously right, the reference.
    Scan,
}

pub struct CpuPipeline {
    settings: PipelineSettings,
    search: Search,
    parallel: bool,
    edge_length: Option<f32>,
    hook: Option<Box<dyn StrokeHook>>,
    /// Where selection and deformation run.
    kernels: Box<dyn StepKernels>,
    region: Region,
    prepared: Option<Prepared>,
    /// Per vertex scratch kept between strokes (reset where used).
    target_of: Vec<u32>,
    touched: Vec<bool>,
}

/// What lasts between strokes: the grid and the collision set-up, with the mesh version they
/// match. Nothing here is recomputed over the whole mesh per stroke.
struct Prepared {
    grid: SpatialHash,
    version: MeshVersion,
    /// Exclusion ring, and the face count it was derived at.
    ring: u32,
    ring_faces: usize,
    /// A running upper bound on edge lengths, and the exact value it started from.
    max_edge: f32,
    exact_max_edge: f32,
}

/// The ring is re-derived when the face count has drifted this much since (remeshing keeps
/// triangle quality, so the ring changes only with large changes of the mesh).
const RING_REFRESH_DRIFT: f64 = 0.05;
/// The edge bound is recomputed exactly when it has grown past this multiple of the exact value.
const EDGE_BOUND_SLACK: f32 = 2.0;

impl CpuPipeline {
    /// The fast backend: grids and all cores.
    pub fn new(settings: PipelineSettings) -> CpuPipeline {
        CpuPipeline::with_search(settings, Search::Grid, true)
    }

    /// The reference: brute-force search on one thread.
    pub fn reference(settings: PipelineSettings) -> CpuPipeline {
        CpuPipeline::with_search(settings, Search::Scan, false)
    }

    pub fn with_search(settings: PipelineSettings, search: Search, parallel: bool) -> CpuPipeline {
        CpuPipeline {
            edge_length: settings.edge_length,
            settings,
            search,
            parallel,
            hook: None,
            kernels: Box::new(CpuKernels),
            region: Region::default(),
            prepared: None,
            target_of: Vec::new(),
            touched: Vec::new(),
        }
    }

    /// Grids and all cores, with selection and deformation done by `kernels` (the GPU's, for
    /// the GPU backend).
    pub fn with_kernels(settings: PipelineSettings, kernels: Box<dyn StepKernels>) -> CpuPipeline {
        CpuPipeline {
            kernels,
            ..CpuPipeline::new(settings)
        }
    }

    /// Why the GPU kernels gave up and the pipeline went on with the CPU's, if they did.
    pub fn kernel_failure(&self) -> Option<String> {
        self.kernels.failure()
    }

    /// Compares the kernels' copy of the mesh (the GPU's), if they keep one, with `mesh`;
    /// `Err` names the first difference. Reads everything back: for tests.
    pub fn check_kernel_copy(&self, mesh: &Mesh) -> Result<(), String> {
        self.kernels.check_copy(mesh)
    }

    /// Runs `hook` after every stroke (remeshing).
    pub fn set_hook(&mut self, hook: Box<dyn StrokeHook>) {
        self.hook = Some(hook);
    }

    /// The edge length `L` the pipeline works with (known after the first stroke).
    pub fn edge_length(&self) -> Option<f32> {
        self.edge_length
    }

    /// Brings the grid and the collision set-up up to date with `mesh`: nothing when the mesh
    /// is as the last stroke left it, a rebuild when something else changed it.
    fn prepare_state(&mut self, mesh: &Mesh) -> Result<(), PipelineError> {
        let edge = match self.edge_length {
            Some(l) => l,
            None => {
                let l = mesh.mean_edge_length();
                if !(l.is_finite() && l > 0.0) {
                    return Err(PipelineError::NoEdges);
                }
                self.edge_length = Some(l);
                l
            }
        };
        let version = mesh.version();
        if let Some(prepared) = &mut self.prepared
            && prepared.version == version
            && !self.settings.rebuild_grid_every_stroke
        {
            if prepared.max_edge > EDGE_BOUND_SLACK * prepared.exact_max_edge {
                prepared.exact_max_edge = longest_edge(mesh, None);
                prepared.max_edge = prepared.exact_max_edge;
            }
            return Ok(());
        }
        // Algorithm 2 rebuilds the grid per stroke. Ours is kept exact by every edit, so it is
        // rebuilt only when something else changed the mesh (or when asked to, for comparison).
        let grid = SpatialHash::build(mesh, edge)?;
        let faces = mesh.face_count();
        let (ring, ring_faces) = match &self.prepared {
            Some(p)
                if (faces as f64 - p.ring_faces as f64).abs()
                    <= RING_REFRESH_DRIFT * p.ring_faces as f64 =>
            {
                (p.ring, p.ring_faces)
            }
            _ => (
                exclusion_ring(mesh, self.settings.collision_distance * edge),
                faces,
            ),
        };
        let exact_max_edge = longest_edge(mesh, None);
        self.prepared = Some(Prepared {
            grid,
            version,
            ring,
            ring_faces,
            max_edge: exact_max_edge,
            exact_max_edge,
        });
        Ok(())
    }
}

/// Remeshes around `seeds` with the pipeline's `L`, collision distance and exclusion ring,
/// keeping `grid` exact, and tells `kernels` what changed.
fn remesh_touched(
    mesh: &mut Mesh,
    (grid, kernels): (&mut SpatialHash, &mut dyn StepKernels),
    seeds: &[u32],
    (edge, distance, ring): (f32, f32, u32),
) -> RemeshReport {
    let settings = RemeshSettings {
        collision_distance: distance,
        exclusion_ring: ring,
        ..RemeshSettings::new(edge)
    };
    let since = mesh.version();
    let (report, changed) = remesh_region(mesh, grid, seeds, &settings);
    kernels.remeshed(mesh, since, &changed);
    report
}

/// Longest edge of the given faces (all live faces when `faces` is `None`).
fn longest_edge(mesh: &Mesh, faces: Option<&[u32]>) -> f32 {
    let edge_max = |f: usize| {
        if mesh.is_face_dead(f) {
            return 0.0f32;
        }
        let [a, b, c] = mesh.face_positions(f);
        a.distance(b).max(b.distance(c)).max(c.distance(a))
    };
    match faces {
        Some(list) => list
            .iter()
            .map(|&f| edge_max(f as usize))
            .fold(0.0, f32::max),
        None => (0..mesh.face_count())
            .into_par_iter()
            .map(edge_max)
            .reduce(|| 0.0, f32::max),
    }
}

/// The dab a sample starts with: at the sample's position, moving from the previous sample's,
/// its frame still to be taken from the selection.
fn probe_at(stroke: &Stroke, sample: &Sample, previous: Option<Vec3>) -> Dab {
    Dab {
        brush: stroke.brush,
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

fn millis(since: Instant) -> f64 {
    since.elapsed().as_secs_f64() * 1e3
}

impl SculptPipeline for CpuPipeline {
    fn prepare(&mut self, mesh: &Mesh) -> Result<(), PipelineError> {
        self.prepare_state(mesh)?;
        if let Some(prepared) = &self.prepared {
            self.kernels.warm_up(mesh, prepared.grid.cell_size());
        }
        Ok(())
    }

    fn uploads(&self) -> Option<Uploads> {
        self.kernels.uploads()
    }

    fn backstop_filter(&self) -> Option<BackstopFilter> {
        self.kernels.backstop_filter()
    }

    fn gpu_memory(&self, mesh: &Mesh) -> Option<GpuMemory> {
        self.kernels.gpu_memory(mesh)
    }

    fn name(&self) -> String {
        let kernels = self.kernels.name();
        if kernels != "cpu" {
            return if self.kernels.collides_on_gpu() {
                format!(
                    "gpu (select, deform, proximity on {kernels}; exact backstop, remesh on the cpu)"
                )
            } else {
                format!("gpu (select, deform on {kernels}; collide, remesh on the cpu)")
            };
        }
        match (self.search, self.parallel) {
            (Search::Grid, true) => "cpu".into(),
            (Search::Scan, false) => "cpu-reference".into(),
            (Search::Grid, false) => "cpu-1-thread".into(),
            (Search::Scan, true) => "cpu-scan".into(),
        }
    }

    fn apply_stroke(
        &mut self,
        mesh: &mut Mesh,
        stroke: &Stroke,
    ) -> Result<StrokeReport, PipelineError> {
        if let Some(&layer) = stroke
            .layers
            .iter()
            .find(|&&l| l as usize >= mesh.layer_count())
        {
            return Err(PipelineError::LayerOutOfRange {
                layer,
                layer_count: mesh.layer_count(),
            });
        }
        let started = Instant::now();
        self.prepare(mesh)?;
        let mut times = PhaseTimes {
            grid_update: millis(started),
            ..PhaseTimes::default()
        };
        let mut report = StrokeReport::default();
        let edge = self.edge_length.unwrap_or(1.0);
        let Some(Prepared {
            mut grid,
            ring,
            mut max_edge,
            exact_max_edge,
            ring_faces,
            ..
        }) = self.prepared.take()
        else {
            return Err(PipelineError::NoEdges);
        };
        let distance = self.settings.collision_distance * edge;

        let mut active = vec![false; mesh.layer_count()];
        for &l in &stroke.layers {
            active[l as usize] = true;
        }
        let step_limit = self.settings.max_step * edge;
        let samples = resample(&stroke.samples, stroke.spacing * stroke.brush.radius);
        report.samples = samples.len();
        let mut target_of = std::mem::take(&mut self.target_of);
        target_of.resize(mesh.vertex_count(), INVALID);
        let mut touched = std::mem::take(&mut self.touched);
        touched.resize(mesh.vertex_count(), false);
        let mut touched_list = Vec::new();
        let mut moved_in_sample = Vec::new();
        let mut previous: Option<Vec3> = None;
        let mut captured: Option<Vec<(u32, f32)>> = None;
        let is_grab = stroke.brush.kind == BrushKind::Grab;
        let deforms = stroke.brush.kind.deforms();
        // Kernels may run the samples ahead while each is one step that nothing else touches
        // between: not a grab (it moves what its first sample caught), not with remeshing
        // between samples.
        let plans_ahead = deforms && !is_grab && self.settings.remeshing != Remeshing::AfterSample;
        if plans_ahead {
            let probes: Vec<SampleProbe> = samples
                .iter()
                .scan(None, |previous, sample| {
                    let probe = probe_at(stroke, sample, *previous);
                    *previous = Some(sample.position);
                    Some((probe, sample.normal))
                })
                .collect();
            self.kernels.upcoming(mesh, &probes);
        }

        let use_grid = self.search == Search::Grid;
        let parallel = self.parallel;
        fn state_for<'a>(
            grid: Option<&'a SpatialHash>,
            active: &'a [bool],
            (parallel, distance, ring, max_edge): (bool, f32, u32, f32),
        ) -> StrokeState<'a> {
            StrokeState {
                grid,
                active,
                parallel,
                collision_distance: distance,
                ring,
                max_edge,
            }
        }
        for sample in &samples {
            let state = state_for(
                use_grid.then_some(&grid),
                &active,
                (parallel, distance, ring, max_edge),
            );
            let started = Instant::now();
            let probe = probe_at(stroke, sample, previous);
            previous = Some(sample.position);
            // A grab keeps the vertices it caught at its first sample; anything else selects
            // anew, and the kernels take the frame and the whole sample's targets with it (on
            // the GPU in one submission, booked under selection: it cannot be split).
            let opened = match (&captured, is_grab) {
                (Some(held), true) => {
                    let frame = brush_frame(mesh, held, &probe, sample.normal);
                    Deformed {
                        selection: held.clone(),
                        frame,
                        targets: None,
                        deform_millis: 0.0,
                    }
                }
                _ => {
                    let source = FrameSource::Selection {
                        normal: sample.normal,
                    };
                    if deforms {
                        self.kernels
                            .select_deform_and_clamp(&state, mesh, &probe, source, step_limit)
                    } else {
                        self.kernels
                            .select_and_deform(&state, mesh, &probe, (source, false))
                    }
                }
            };
            let Deformed {
                selection: first_selection,
                frame,
                targets: opened_targets,
                deform_millis,
            } = opened;
            if is_grab && captured.is_none() {
                captured = Some(first_selection.clone());
            }
            times.selection += millis(started) - deform_millis;
            times.deformation += deform_millis;
            if first_selection.is_empty() {
                continue;
            }

            // Paint in the same pass as the deformation, where the brush is before it moves
            // anything; booked under deformation.
            if let Some(spec) = &stroke.paint {
                let started = Instant::now();
                let dab = Dab { frame, ..probe };
                let painted = paint(&state, mesh, &dab, &first_selection, spec);
                let brdfs = mesh.brdfs_mut();
                for (&(v, _), brdf) in first_selection.iter().zip(painted) {
                    brdfs[v as usize] = brdf;
                }
                times.deformation += millis(started);
            }
            if !deforms {
                continue;
            }

            // Split the sample's motion into steps of at most `max_step` edge lengths.
            let started = Instant::now();
            let whole = Dab { frame, ..probe };
            let mut full = match opened_targets {
                Some(targets) => targets,
                None => self.kernels.deform(&state, mesh, &whole, &first_selection),
            };
            let steps = steps_for(longest_move(mesh, &first_selection, &full), step_limit);
            times.deformation += millis(started);
            moved_in_sample.clear();

            for step in 0..steps {
                let state = state_for(
                    use_grid.then_some(&grid),
                    &active,
                    (parallel, distance, ring, max_edge),
                );
                let dab = Dab {
                    share: 1.0 / steps as f32,
                    ..whole
                };
                // A sample taken in one step moves the selection exactly as its whole motion
                // did (same vertices, share 1): its targets are already known. Later steps
                // select anew under the dab and deform in the same call (one submission on
                // the GPU, booked under selection there).
                let started = Instant::now();
                let (selection, targets) = if step == 0 || is_grab {
                    let targets = if steps == 1 {
                        std::mem::take(&mut full)
                    } else {
                        self.kernels.deform(&state, mesh, &dab, &first_selection)
                    };
                    times.deformation += millis(started);
                    (first_selection.clone(), targets)
                } else {
                    let step_pass = self.kernels.select_deform_and_clamp(
                        &state,
                        mesh,
                        &dab,
                        FrameSource::Dab,
                        step_limit,
                    );
                    times.selection += millis(started) - step_pass.deform_millis;
                    times.deformation += step_pass.deform_millis;
                    (step_pass.selection, step_pass.targets.unwrap_or_default())
                };

                let started = Instant::now();
                for (i, &(v, _)) in selection.iter().enumerate() {
                    target_of[v as usize] = i as u32;
                }
                let before: Vec<Vec3> = selection
                    .iter()
                    .map(|&(v, _)| mesh.positions()[v as usize])
                    .collect();
                let kernels = &mut self.kernels;
                let moves = (
                    selection.as_slice(),
                    targets.as_slice(),
                    target_of.as_slice(),
                );
                let outcome = collide_with(
                    &state,
                    &mut self.region,
                    mesh,
                    moves,
                    |region, mesh, before| kernels.clamp(&state, region, mesh, moves, before),
                );
                for &(v, _) in &selection {
                    target_of[v as usize] = INVALID;
                }
                let moved: Vec<u32> = selection
                    .iter()
                    .zip(&before)
                    .zip(&outcome.positions)
                    .filter(|((_, p), q)| p != q)
                    .map(|((&(v, _), _), _)| v)
                    .collect();
                let selected: Vec<u32> = selection.iter().map(|&(v, _)| v).collect();
                let step_move = largest_move(&before, &outcome.positions);
                self.kernels.moved(mesh, &selected, step_move);
                let mut moved_faces: Vec<u32> =
                    moved.iter().flat_map(|&v| mesh.faces_around(v)).collect();
                moved_faces.sort_unstable();
                moved_faces.dedup();
                max_edge = max_edge.max(longest_edge(mesh, Some(&moved_faces)));
                times.collision += millis(started);

                let started = Instant::now();
                for &v in &moved {
                    grid.move_to(v, mesh.positions()[v as usize]);
                }
                times.grid_update += millis(started);

                report.steps += 1;
                report.moves += moved.len();
                report.clamped += outcome.clamped;
                report.reverted += outcome.reverted;
                for v in moved {
                    if !touched[v as usize] {
                        touched[v as usize] = true;
                        touched_list.push(v);
                    }
                    moved_in_sample.push(v);
                }
            }

            // Normals of the moved vertices and of their neighbours, whose faces also turned.
            let started = Instant::now();
            let mut refresh: Vec<u32> = moved_in_sample
                .iter()
                .flat_map(|&v| mesh.faces_around(v).flat_map(|f| mesh.faces()[f as usize]))
                .collect();
            refresh.sort_unstable();
            refresh.dedup();
            mesh.recompute_normals_at(&refresh);
            self.kernels.normals_changed(mesh, &refresh);
            times.deformation += millis(started);

            // A grab keeps moving the vertices it caught at its first sample, so its region is
            // remeshed once, after the stroke.
            if self.settings.remeshing == Remeshing::AfterSample && !is_grab {
                let started = Instant::now();
                let pass = remesh_touched(
                    mesh,
                    (&mut grid, self.kernels.as_mut()),
                    &moved_in_sample,
                    (edge, distance, ring),
                );
                max_edge = max_edge.max(pass.longest_edge);
                report.remesh.add(&pass);
                target_of.resize(mesh.vertex_count(), INVALID);
                touched.resize(mesh.vertex_count(), false);
                times.remesh += millis(started);
            }
        }

        if plans_ahead {
            self.kernels.upcoming(mesh, &[]);
        }
        touched_list.sort_unstable();
        for &v in &touched_list {
            touched[v as usize] = false;
        }
        self.target_of = target_of;
        self.touched = touched;
        report.touched = touched_list.len();
        let remesh_now = match self.settings.remeshing {
            Remeshing::Off => false,
            Remeshing::AfterStroke => true,
            Remeshing::AfterSample => is_grab,
        };
        if remesh_now {
            let started = Instant::now();
            let pass = remesh_touched(
                mesh,
                (&mut grid, self.kernels.as_mut()),
                &touched_list,
                (edge, distance, ring),
            );
            max_edge = max_edge.max(pass.longest_edge);
            report.remesh.add(&pass);
            times.remesh += millis(started);
        }
        let mut grid_current = true;
        if let Some(hook) = self.hook.as_mut() {
            let started = Instant::now();
            grid_current = hook.after_stroke(mesh, &touched_list, &mut grid)?;
            // The hook edits faces around the stroke only: their edges bound the change.
            let around: Vec<u32> = touched_list
                .iter()
                .filter(|&&v| (v as usize) < mesh.vertex_count() && !mesh.is_vertex_dead(v))
                .flat_map(|&v| mesh.faces_around(v))
                .collect();
            max_edge = max_edge.max(longest_edge(mesh, Some(&around)));
            times.remesh += millis(started);
        }
        if grid_current {
            self.prepared = Some(Prepared {
                grid,
                version: mesh.version(),
                ring,
                ring_faces,
                max_edge,
                exact_max_edge,
            });
        }
        report.phases = times;
        Ok(report)
    }
}
