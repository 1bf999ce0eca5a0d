//! [`Pipeline`]: what lasts between strokes — the grid, the collision set-up, the kernels that
//! select and deform (the CPU's or the GPU's) — and the door strokes come in by
//! ([`Pipeline::begin_stroke`]).

use std::time::Instant;

use rayon::prelude::*;

use super::kernels::{CpuKernels, EngineVertices, StepKernels};
use super::stroke::StrokeInProgress;
use super::{
    BackstopFilter, GpuMemory, PhaseTimes, PipelineError, PipelineSettings, Remeshing,
    StrokeReport, Uploads,
};
use crate::brush::{Stroke, StrokeSettings};
use crate::collide::Region;
use crate::collide::neighbourhood::exclusion_ring;
use crate::grid::SpatialHash;
use crate::mesh::{INVALID, Mesh, MeshVersion};
use crate::remesh::{RemeshReport, RemeshSets, RemeshSettings, remesh_region_with};
use crate::topology::{FuseSettings, TopologyReport, adapt};

/// sLayer's Algorithm 2 over one mesh, on every backend: the loop, the exact backstop and
/// remeshing run here on the CPU; selection, deformation and (on a GPU) the proximity passes
/// run in its [`StepKernels`].
pub struct Pipeline {
    pub(super) settings: PipelineSettings,
    /// The reference: nearby elements found by scanning every vertex and face, on one thread
    /// (slow, obviously right); otherwise through the spatial hash and a per-step face grid, on
    /// all cores.
    pub(super) reference: bool,
    pub(super) edge_length: Option<f32>,
    /// Where selection and deformation run.
    pub(super) kernels: Box<dyn StepKernels>,
    /// Kept between strokes so that a stroke does not allocate them anew (reset where used).
    pub(super) scratch: Scratch,
    pub(super) prepared: Option<Prepared>,
}

/// Per-vertex scratch and the collision region, kept between strokes.
#[derive(Default)]
pub(super) struct Scratch {
    pub region: Region,
    /// Per vertex: its index in the current step's selection, or `INVALID`.
    pub target_of: Vec<u32>,
    /// Per vertex: whether the stroke moved it.
    pub touched: Vec<bool>,
    /// Vertices met already, to list each once without sorting duplicates away.
    pub vertex_marks: crate::collide::Stamps,
    /// The remesher's per-vertex sets.
    pub remesh: RemeshSets,
}

impl Scratch {
    /// Sizes every per-vertex and per-face array for `mesh` (growing gently, never
    /// shrinking), so that a stroke allocates none of them.
    pub fn size_for(&mut self, mesh: &Mesh) {
        crate::grow::grow_to(&mut self.target_of, mesh.vertex_count(), INVALID);
        crate::grow::grow_to(&mut self.touched, mesh.vertex_count(), false);
        self.vertex_marks.size_for(mesh.vertex_count());
        self.region.size_for(mesh);
        self.remesh.size_for(mesh);
    }
}

/// What lasts between strokes: the grid and the collision set-up, with the mesh version they
/// match. Nothing here is recomputed over the whole mesh per stroke.
pub(super) struct Prepared {
    pub grid: SpatialHash,
    pub version: MeshVersion,
    /// Exclusion ring, and the face count it was derived at.
    pub ring: u32,
    pub ring_faces: usize,
    /// A running upper bound on edge lengths, and the exact value it started from.
    pub max_edge: f32,
    pub exact_max_edge: f32,
}

/// The ring is re-derived when the face count has drifted this much since (remeshing keeps
/// triangle quality, so the ring changes only with large changes of the mesh).
const RING_REFRESH_DRIFT: f64 = 0.05;
/// The edge bound is recomputed exactly when it has grown past this multiple of the exact value.
const EDGE_BOUND_SLACK: f32 = 2.0;

impl Pipeline {
    /// The fast backend: grids and all cores.
    pub fn new(settings: PipelineSettings) -> Pipeline {
        Pipeline::with_reference(settings, false)
    }

    /// The reference: brute-force search on one thread.
    pub fn reference(settings: PipelineSettings) -> Pipeline {
        Pipeline::with_reference(settings, true)
    }

    fn with_reference(settings: PipelineSettings, reference: bool) -> Pipeline {
        Pipeline {
            edge_length: settings.edge_length,
            settings,
            reference,
            kernels: Box::new(CpuKernels),
            scratch: Scratch::default(),
            prepared: None,
        }
    }

    /// Grids and all cores, with selection and deformation done by `kernels` (the GPU's, for
    /// the GPU backend).
    pub fn with_kernels(settings: PipelineSettings, kernels: Box<dyn StepKernels>) -> Pipeline {
        Pipeline {
            kernels,
            ..Pipeline::new(settings)
        }
    }

    pub fn settings(&self) -> &PipelineSettings {
        &self.settings
    }

    /// When the next strokes remesh (the app's "remesh" switch).
    pub fn set_remeshing(&mut self, remeshing: Remeshing) {
        self.settings.remeshing = remeshing;
    }

    /// Starts a stroke on `mesh`: its samples come in with
    /// [`StrokeInProgress::add_samples`] as they are drawn, and
    /// [`StrokeInProgress::finish`] remeshes what it touched. Brings the grid up to date with
    /// `mesh` first (nothing to do when the last stroke left it as it is).
    pub fn begin_stroke<'a>(
        &'a mut self,
        mesh: &'a mut Mesh,
        stroke: StrokeSettings,
    ) -> Result<StrokeInProgress<'a>, PipelineError> {
        StrokeInProgress::begin(self, mesh, stroke)
    }

    /// Whether [`Pipeline::begin_stroke`] would take `stroke` on `mesh`: its layers exist and
    /// its brush is within bounds for the mesh's size. Nothing runs either way.
    pub fn check_stroke(mesh: &Mesh, stroke: &StrokeSettings) -> Result<(), PipelineError> {
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
        if let Some(&layer) = stroke.fuse.iter().find(|l| !stroke.layers.contains(l)) {
            return Err(PipelineError::InvalidBrush(format!(
                "fuse names layer {layer}, which the stroke does not brush"
            )));
        }
        // A mesh with no vertices has no size to measure the brush by; it has no edges either,
        // which `begin_stroke` reports.
        if let Some(extent) = mesh.extent() {
            let extent = extent.max(f32::MIN_POSITIVE);
            stroke.check(extent).map_err(PipelineError::InvalidBrush)?;
        }
        Ok(())
    }

    /// A whole stroke: [`Pipeline::begin_stroke`], then its samples and its end in one
    /// [`StrokeInProgress::finish_with`] (the same mesh as `add_samples` then `finish`).
    pub fn apply_stroke(
        &mut self,
        mesh: &mut Mesh,
        stroke: &Stroke,
    ) -> Result<StrokeReport, PipelineError> {
        self.begin_stroke(mesh, stroke.settings())?
            .finish_with(&stroke.samples)
    }

    /// Name for reports: "cpu", "cpu-reference", or what runs where on the GPU.
    pub fn name(&self) -> String {
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
        if self.reference {
            "cpu-reference".into()
        } else {
            "cpu".into()
        }
    }

    /// Builds what strokes need (grid, uploads) ahead of time; a stroke does it when needed,
    /// so calling this only moves the one-time cost out of the first stroke.
    pub fn prepare(&mut self, mesh: &Mesh) -> Result<(), PipelineError> {
        self.prepare_state(mesh)?;
        self.scratch.size_for(mesh);
        if let Some(prepared) = &self.prepared {
            self.kernels.warm_up(mesh, prepared.grid.cell_size());
        }
        Ok(())
    }

    /// Forgets the mesh it worked on — its edge length, grid and the kernels' copy — for a
    /// pipeline that goes on with another mesh (the app opening a file): the pipeline keeps the
    /// edge length it first measured. (The grid and the copy would be rebuilt anyway: another
    /// mesh's [`MeshVersion`] differs.)
    pub fn forget_mesh(&mut self) {
        self.edge_length = None;
        self.prepared = None;
        self.kernels.forget_mesh();
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

    /// Kernels that keep a copy of the mesh elsewhere (the GPU's): how they kept it current.
    pub fn uploads(&self) -> Option<Uploads> {
        self.kernels.uploads()
    }

    /// Kernels that filter the backstop's pairs elsewhere (the GPU's): what they left the CPU.
    pub fn backstop_filter(&self) -> Option<BackstopFilter> {
        self.kernels.backstop_filter()
    }

    /// Kernels that keep a copy of the mesh on a GPU: their position and normal buffers,
    /// current with `mesh` (what differs is sent first), for a viewport on the same device
    /// (the caller's to know: the app's window shares the backend's device or not).
    pub fn vertex_buffers(&mut self, mesh: &Mesh) -> Option<EngineVertices> {
        self.kernels.vertex_buffers(mesh)
    }

    /// Kernels that keep `mesh` in GPU memory: how much they hold now.
    pub fn gpu_memory(&self, mesh: &Mesh) -> Option<GpuMemory> {
        self.kernels.gpu_memory(mesh)
    }

    /// The running upper bound on the mesh's edge lengths that bounds the collision searches
    /// (known once prepared); never below the longest edge.
    pub fn edge_bound(&self) -> Option<f32> {
        self.prepared.as_ref().map(|p| p.max_edge)
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
        // The grid holds positions and the live vertices: a mask or paint edit between
        // strokes leaves it as it is.
        if let Some(prepared) = &mut self.prepared
            && prepared.version.topology == version.topology
            && prepared.version.positions == version.positions
        {
            if prepared.max_edge > EDGE_BOUND_SLACK * prepared.exact_max_edge {
                prepared.exact_max_edge = longest_edge(mesh, None);
                prepared.max_edge = prepared.exact_max_edge;
            }
            return Ok(());
        }
        // Algorithm 2 rebuilds the grid per stroke. Ours is kept exact by every edit, so it is
        // rebuilt only when something else changed the mesh.
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

    /// [`Pipeline::prepare`], timed: the milliseconds it took, and what it prepared (taken out
    /// of the pipeline for the stroke, which puts it back when it ends).
    pub(super) fn take_prepared(
        &mut self,
        mesh: &Mesh,
    ) -> Result<(Prepared, PhaseTimes), PipelineError> {
        let started = Instant::now();
        self.prepare(mesh)?;
        let times = PhaseTimes {
            grid_update: millis(started),
            ..PhaseTimes::default()
        };
        let prepared = self.prepared.take().ok_or(PipelineError::NoEdges)?;
        Ok((prepared, times))
    }
}

/// Remeshes around `seeds` with the pipeline's `L`, collision distance and exclusion ring (and
/// at most `max_splits` splits: what is left of the stroke's bound on new faces), letting a
/// sheet zone settle its edits' checks where `culling` gives the mesh's longest edge,
/// keeping `grid` exact, and tells `kernels` what changed; returns what it did and the
/// vertices it changed (ascending).
pub(super) fn remesh_touched(
    mesh: &mut Mesh,
    (grid, kernels, sets): (&mut SpatialHash, &mut dyn StepKernels, &mut RemeshSets),
    (seeds, culling): (&[u32], Option<f32>),
    (edge, distance, ring, max_splits): (f32, f32, u32, usize),
) -> (RemeshReport, Vec<u32>) {
    let settings = RemeshSettings {
        collision_distance: distance,
        exclusion_ring: ring,
        max_splits,
        ..RemeshSettings::new(edge)
    };
    let since = mesh.version();
    let (report, changed) = remesh_region_with(mesh, grid, seeds, (&settings, culling), sets);
    kernels.remeshed(mesh, since, &changed);
    (report, changed)
}

/// After a stroke: joins and splits its fuse layers where they touch themselves near `seeds`
/// (`crate::topology`), keeping `grid` exact and telling `kernels` what changed. Nothing
/// without fuse layers.
pub(super) fn fuse_touched(
    mesh: &mut Mesh,
    (grid, kernels): (&mut SpatialHash, &mut dyn StepKernels),
    (fuse_layers, seeds): (&[u32], &[u32]),
    (edge, distance, ring): (f32, f32, u32),
) -> TopologyReport {
    if fuse_layers.is_empty() {
        return TopologyReport::default();
    }
    let mut fuse = vec![false; mesh.layer_count()];
    for &l in fuse_layers {
        fuse[l as usize] = true;
    }
    let settings = FuseSettings::with_ring(edge, distance, ring);
    let since = mesh.version();
    let report = adapt(mesh, grid, &fuse, seeds, &settings);
    if !report.changed.is_empty() {
        kernels.remeshed(mesh, since, &report.changed);
    }
    report
}

/// Longest edge of the given faces (all live faces when `faces` is `None`).
pub(super) fn longest_edge(mesh: &Mesh, faces: Option<&[u32]>) -> f32 {
    let Some(list) = faces else {
        return mesh.longest_edge();
    };
    let edge_max = |f: usize| {
        if mesh.is_face_dead(f) {
            return 0.0f32;
        }
        let [a, b, c] = mesh.face_positions(f);
        a.distance(b).max(b.distance(c)).max(c.distance(a))
    };
    list.iter()
        .map(|&f| edge_max(f as usize))
        .fold(0.0, f32::max)
}

/// The longest edge at `vertices`: after they moved, the only edges whose length changed.
pub(super) fn longest_edge_at(mesh: &Mesh, vertices: &[u32]) -> f32 {
    let positions = mesh.positions();
    vertices
        .par_iter()
        .map(|&v| {
            // Each neighbour once: around a vertex inside the mesh, a corner's next and
            // prev edges are its neighbours' prev and next.
            let p = positions[v as usize];
            mesh.ring(v)
                .map(|w| p.distance_squared(positions[w as usize]))
                .fold(0.0f32, f32::max)
        })
        .reduce(|| 0.0, f32::max)
        // One root for all: a correctly rounded root keeps the order, so the same length.
        .sqrt()
}

pub(super) fn millis(since: Instant) -> f64 {
    since.elapsed().as_secs_f64() * 1e3
}
