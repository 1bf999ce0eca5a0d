//! The brush pipeline: sLayer's Algorithm 2 behind one interface that every backend implements.
//!
//! Per stroke the grid is rebuilt; per sample the brush's motion is split into steps of at most
//! one edge length; per step vertices are selected through the grid, deformed, tested against
//! nearby triangles and clamped where they would come closer than the collision distance; an
//! exact backstop then undoes any move that would still make two triangles cross (edge–edge
//! cases the vertex–triangle test cannot see). After the stroke the region it touched is
//! remeshed. Every backend reports the same phases: selection, deformation, grid update,
//! collision, remesh.
//!
//! Strokes stream: [`Pipeline::begin_stroke`] → [`StrokeInProgress::add_samples`] as samples
//! are drawn → [`StrokeInProgress::finish`]. [`Pipeline::apply_stroke`] is the three at once.
//! `docs/strokes.md` has the stroke file and this example:
//!
//! ```
//! use glam::Vec3;
//! use slayer::brush::{Brush, BrushKind, Falloff, Sample, StrokeSettings};
//! use slayer::pipeline::{Pipeline, PipelineSettings};
//! use slayer::scene::{SceneKind, SceneSpec, generate};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let mut mesh = generate(&SceneSpec { kind: SceneKind::Plaster, triangles: 2_000, seed: 1 })?;
//! let mut pipeline = Pipeline::new(PipelineSettings::default());
//! let brush = Brush { kind: BrushKind::Draw, radius: 0.1, strength: 0.5,
//!                     falloff: Falloff::default(), invert: true };
//! let mut stroke = pipeline.begin_stroke(&mut mesh, StrokeSettings {
//!     brush, paint: None, layers: vec![1], spacing: 0.25, symmetry: None, fuse: vec![],
//! })?;
//! for x in [0.3f32, 0.35, 0.4, 0.45, 0.5] {
//!     // One pointer event: the samples it completes run now.
//!     let done = stroke.add_samples(&[Sample {
//!         position: Vec3::new(x, 0.5, 0.15), pressure: 1.0, normal: None,
//!     }])?;
//!     // `done.changed`: the vertices to upload again; `done.topology_changed`: the faces too.
//!     assert!(done.changed.windows(2).all(|w| w[0] < w[1]));
//! }
//! let report = stroke.finish()?; // runs the last sample, remeshes what the stroke touched
//! assert!(report.moves > 0);
//! println!("{} samples, {} moves, {} clamped", report.samples, report.moves, report.clamped);
//! # Ok(())
//! # }
//! ```

mod engine;
mod kernels;
pub mod step;
mod stroke;

pub use engine::Pipeline;
pub use kernels::{
    BackstopFilter, CallAt, CpuKernels, Deformed, EngineVertices, FrameSource, GateStops,
    GpuMemory, SampleProbe, StepKernels, Uploads,
};
pub use stroke::{SamplesReport, StrokeInProgress};

use serde::Serialize;
use thiserror::Error;

use crate::grid::GridError;
use crate::remesh::RemeshReport;
use crate::topology::TopologyReport;

/// Tunables, in units of the mesh's edge length `L` where they are lengths.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PipelineSettings {
    /// Vertices stop this far (× L) from other surfaces. The paper uses one edge length.
    pub collision_distance: f32,
    /// Largest move of a vertex in one step (× L). Below twice the collision distance a vertex
    /// cannot jump across a triangle between two proximity tests.
    pub max_step: f32,
    /// The edge length `L`; by default the mean edge length of the mesh at the first stroke,
    /// then held constant (sLayer's edge length assumption).
    pub edge_length: Option<f32>,
    /// When the touched region is remeshed back to edge length `L`.
    pub remeshing: Remeshing,
    /// The most dabs (samples after resampling) one stroke may make; samples that would take a
    /// stroke past it are refused with [`PipelineError::TooManyDabs`] before they run.
    pub max_dabs_per_stroke: usize,
    /// The faces one stroke's remeshing may create: this many, or as many as the mesh had when
    /// the stroke began where that is more. Past it, splits are left undone (edges stay long;
    /// [`RemeshReport::growth_capped`]), so that a stroke can neither exhaust memory nor run
    /// for minutes crumpling a layer into ever more faces.
    pub new_faces_per_stroke: usize,
    /// The longest (× L) a stroke may stretch an edge before remeshing refines it, or the
    /// longest edge the mesh had when the stroke began where that is more: the step that
    /// stretches one past it is the stroke's last, and what it did is kept
    /// ([`StrokeReport::stopped_stretched`]). Collision searches cost more the longer the
    /// faces: a sweep twelve times the size of a 52K-face sphere smeared it into slivers of
    /// 100 edge lengths, and ran for 25 minutes.
    pub max_stretch: f32,
    /// Skip the collision searches that provably find nothing: within a layer where it is a
    /// sheet that cannot touch itself, against other layers where none is near
    /// (`collide::sheet`). The result is the same, bit for bit; off only to compare
    /// (`slayer bench --no-cull`).
    pub cull: bool,
}

/// [`PipelineSettings::max_stretch`] by default: 32 edge lengths (that sweep stretched edges by
/// 0.77 L a step; stopped at 32 L it takes 26 s; no stroke of `slayer bench`'s scenes comes
/// near it).
pub const MAX_STRETCH: f32 = 32.0;

/// [`PipelineSettings::new_faces_per_stroke`] by default: 2¹⁶ faces (a crease over the whole of
/// a 53K-face plaster crumpled its paint layer to 159K faces in one stroke, 2 minutes).
pub const NEW_FACES_PER_STROKE: usize = 1 << 16;

/// When the pipeline remeshes what the brush touched (sLayer discusses both; docs/design.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Remeshing {
    /// Never: edges stretch and shrink with the brush.
    Off,
    /// Once per stroke, over every vertex the stroke moved (the paper's choice, and ours). A
    /// grab is also remeshed between its samples wherever it stretched an edge past 2·`L`, so
    /// a long drag costs in proportion to its length.
    #[default]
    AfterStroke,
    /// After every stroke sample, over the vertices that sample moved: strong grabs keep their
    /// detail while they stretch, at the price of more remeshing passes.
    AfterSample,
}

impl std::str::FromStr for Remeshing {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "off" => Ok(Remeshing::Off),
            "stroke" => Ok(Remeshing::AfterStroke),
            "sample" => Ok(Remeshing::AfterSample),
            other => Err(format!(
                "unknown remeshing `{other}` (expected off, stroke or sample)"
            )),
        }
    }
}

impl PipelineSettings {
    /// The faces a stroke that begins on a mesh of `faces` may create by remeshing
    /// ([`PipelineSettings::new_faces_per_stroke`], or `faces` where that is more).
    pub fn new_faces_bound(&self, faces: usize) -> usize {
        self.new_faces_per_stroke.max(faces)
    }
}

impl Default for PipelineSettings {
    fn default() -> Self {
        PipelineSettings {
            collision_distance: 1.0,
            max_step: 1.0,
            edge_length: None,
            remeshing: Remeshing::AfterStroke,
            max_dabs_per_stroke: crate::brush::MAX_DABS_PER_STROKE,
            new_faces_per_stroke: NEW_FACES_PER_STROKE,
            max_stretch: MAX_STRETCH,
            cull: true,
        }
    }
}

/// Milliseconds spent in each phase.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct PhaseTimes {
    pub selection: f64,
    pub deformation: f64,
    pub grid_update: f64,
    pub collision: f64,
    pub remesh: f64,
}

impl PhaseTimes {
    pub fn total(&self) -> f64 {
        self.selection + self.deformation + self.grid_update + self.collision + self.remesh
    }

    pub fn add(&mut self, other: &PhaseTimes) {
        self.selection += other.selection;
        self.deformation += other.deformation;
        self.grid_update += other.grid_update;
        self.collision += other.collision;
        self.remesh += other.remesh;
    }

    /// The phases as (name, milliseconds), in table order.
    pub fn named(&self) -> [(&'static str, f64); 5] {
        [
            ("selection", self.selection),
            ("deformation", self.deformation),
            ("grid update", self.grid_update),
            ("collision", self.collision),
            ("remesh", self.remesh),
        ]
    }
}

/// What one stroke did.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct StrokeReport {
    /// Samples after resampling.
    pub samples: usize,
    /// Steps (a sample moving vertices more than `max_step` takes several).
    pub steps: usize,
    /// Vertex moves, summed over steps.
    pub moves: usize,
    /// Moves shortened by the proximity test.
    pub clamped: usize,
    /// Moves undone by the exact backstop.
    pub reverted: usize,
    /// Samples whose move needed more than [`step::MAX_STEPS_PER_SAMPLE`] steps (a runaway brush):
    /// each moved only that many steps of at most `max_step`.
    pub capped_samples: usize,
    /// Steps whose collision searches within a layer were skipped, the layer being a sheet
    /// that cannot touch itself there ([`PipelineSettings::cull`]).
    pub culled_steps: usize,
    /// Moving vertices the collision response did not search, their own neighbourhood
    /// clearing them ([`SamplesReport::culled_vertices`]).
    pub culled_vertices: usize,
    /// Distinct vertices the stroke moved.
    pub touched: usize,
    /// What remeshing did, summed over the stroke's remeshing passes.
    pub remesh: RemeshReport,
    /// The faces the stroke's remeshing was allowed to create
    /// ([`PipelineSettings::new_faces_bound`] of the mesh it began on).
    pub new_faces_bound: usize,
    /// The stroke stopped early: a step stretched an edge to this length (× L), past
    /// [`PipelineSettings::max_stretch`]; the samples after it were not run.
    pub stopped_stretched: Option<f32>,
    /// Joins and splits of fuse layers after the stroke (`crate::topology`).
    pub topology: TopologyReport,
    pub phases: PhaseTimes,
    /// Vertices the last call (`finish`: its last samples and the remeshing after the stroke)
    /// changed, ascending, vertices remeshing added or removed among them: what a viewer
    /// uploads again after the stroke, with the faces when `remesh` edited any.
    #[serde(skip)]
    pub changed: Vec<u32>,
}

impl StrokeReport {
    /// Counts and phase times of one [`StrokeInProgress::add_samples`] call, added in.
    pub(crate) fn add_call(&mut self, call: &SamplesReport) {
        self.samples += call.samples;
        self.steps += call.steps;
        self.moves += call.moves;
        self.clamped += call.clamped;
        self.reverted += call.reverted;
        self.capped_samples += call.capped_samples;
        self.culled_steps += call.culled_steps;
        self.culled_vertices += call.culled_vertices;
        self.stopped_stretched = self.stopped_stretched.or(call.stopped_stretched);
        self.phases.add(&call.phases);
    }
}

#[derive(Debug, Error)]
pub enum PipelineError {
    #[error("the mesh has no edges to take a length from")]
    NoEdges,
    #[error("stroke names layer {layer}, but the mesh has {layer_count}")]
    LayerOutOfRange { layer: u32, layer_count: usize },
    #[error(transparent)]
    Grid(#[from] GridError),
    #[error("the stroke has ended")]
    StrokeEnded,
    /// The stroke's brush is out of bounds ([`StrokeSettings::check`](crate::brush::StrokeSettings::check)):
    /// nothing ran.
    #[error("{0}")]
    InvalidBrush(String),
    /// Samples were refused: they would make the stroke more dabs than its bound. The mesh and
    /// the stroke are as they were before the call.
    #[error(transparent)]
    TooManyDabs(#[from] crate::brush::DabLimit),
}
