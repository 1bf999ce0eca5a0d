//! `slayer bench` (BENCHMARK.md): generated scenes, a seeded stroke script, the paper's Table 1
//! layout, and the scaling run.

mod report;
mod script;

pub use report::{paper_table, scaling_svg, scaling_table};
pub use script::{BrushMix, ScriptSpec, generate_script};

use serde::Serialize;

use crate::brush::Stroke;
use crate::collide::find_intersections;
use crate::mesh::Mesh;
use crate::pipeline::{PhaseTimes, PipelineError, SculptPipeline};

/// Figures for one scene; field names are the fixed JSON interface of BENCHMARK.md.
#[derive(Debug, Clone, Serialize)]
pub struct SceneResult {
    pub name: String,
    pub layers: usize,
    pub vertices: usize,
    pub faces: usize,
    pub mean_edge_length: f64,
    pub strokes: usize,
    pub samples: usize,
    pub steps: usize,
    pub phase_ms: PhaseTimes,
    pub ms_per_sample: f64,
    pub ms_per_stroke: f64,
    pub ms_per_remesh: f64,
    pub intersections: usize,
    pub edge_band_fraction: f64,
    pub valid: bool,
    pub faces_after: usize,
    /// One-time set-up before the first stroke (grid build, collision set-up), not in the
    /// per-sample figures.
    pub setup_ms: f64,
    /// Moves shortened by the proximity test, and undone by the exact backstop.
    pub collisions: usize,
    pub reverted: usize,
    pub moves: usize,
    pub validation_error: Option<String>,
}

/// One row of the scaling run.
#[derive(Debug, Clone, Serialize)]
pub struct ScalingRow {
    pub faces: usize,
    pub ms_per_sample: f64,
    pub ms_per_remesh: f64,
    /// Work done, to check that every size did the same: samples, steps, vertex moves.
    pub samples: usize,
    pub steps: usize,
    pub moves: usize,
}

/// Runs `strokes` on `mesh` and measures. `progress` is told after each stroke.
pub fn run_strokes(
    name: &str,
    mesh: &mut Mesh,
    strokes: &[Stroke],
    pipeline: &mut dyn SculptPipeline,
    mut progress: impl FnMut(usize),
    check_intersections: bool,
) -> Result<SceneResult, PipelineError> {
    let (vertices, faces) = (mesh.live_vertex_count(), mesh.live_face_count());
    let mean_edge_length = mesh.edge_length_stats().mean;
    let started = std::time::Instant::now();
    pipeline.prepare(mesh)?;
    let setup_ms = started.elapsed().as_secs_f64() * 1e3;
    let mut phases = PhaseTimes::default();
    let (mut samples, mut steps, mut collisions, mut reverted, mut moves) = (0, 0, 0, 0, 0);
    for (i, stroke) in strokes.iter().enumerate() {
        let report = pipeline.apply_stroke(mesh, stroke)?;
        phases.add(&report.phases);
        samples += report.samples;
        steps += report.steps;
        collisions += report.clamped;
        reverted += report.reverted;
        moves += report.moves;
        progress(i + 1);
    }
    let sampling_ms = phases.total() - phases.remesh;
    let validation = mesh.validate();
    let intersections = if check_intersections {
        find_intersections(mesh).total()
    } else {
        0
    };
    let band = edge_band_fraction(mesh, mean_edge_length);
    Ok(SceneResult {
        name: name.to_string(),
        layers: mesh.layer_count(),
        vertices,
        faces,
        mean_edge_length,
        strokes: strokes.len(),
        samples,
        steps,
        phase_ms: phases,
        ms_per_sample: sampling_ms / samples.max(1) as f64,
        ms_per_stroke: phases.total() / strokes.len().max(1) as f64,
        ms_per_remesh: phases.remesh / strokes.len().max(1) as f64,
        intersections,
        edge_band_fraction: band,
        valid: validation.is_ok(),
        validation_error: validation.err().map(|e| e.to_string()),
        faces_after: mesh.live_face_count(),
        setup_ms,
        collisions,
        reverted,
        moves,
    })
}

/// Share of edges with length in [4/5·L, 4/3·L] (the remesher's band).
pub fn edge_band_fraction(mesh: &Mesh, edge: f64) -> f64 {
    let (lo, hi) = (0.8 * edge, 4.0 / 3.0 * edge);
    let mut inside = 0usize;
    let mut total = 0usize;
    mesh.for_each_edge(|a, b| {
        let l = mesh.positions()[a as usize].distance(mesh.positions()[b as usize]) as f64;
        total += 1;
        if (lo..=hi).contains(&l) {
            inside += 1;
        }
    });
    inside as f64 / total.max(1) as f64
}

/// The short git revision of the working copy, if git can tell.
pub fn git_revision() -> String {
    std::process::Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into())
}
