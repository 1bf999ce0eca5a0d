//! `slayer bench` (docs/bench.md): generated scenes, a seeded stroke script, the paper's Table 1
//! layout, and the scaling run.

mod report;
mod script;

pub use report::{gpu_memory_lines, paper_table, scaling_svg, scaling_table, topology_lines};
pub use script::{BrushMix, ScriptSpec, generate_script};

use serde::Serialize;

use crate::brush::{Stroke, StrokeSettings};
use crate::collide::find_intersections;
use crate::mesh::Mesh;
use crate::pipeline::{
    BackstopFilter, GateStops, GpuMemory, PhaseTimes, Pipeline, PipelineError, StrokeReport,
    Uploads,
};
use crate::remesh::RemeshReport;
pub use crate::remesh::{AngleSummary, smallest_angle_degrees};
use crate::topology::TopologyReport;

/// Figures for one scene; field names are the fixed JSON interface of docs/bench.md.
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
    /// With `--policy fuse`: the joins and splits the strokes made, and their cost.
    pub topology: Option<TopologyFigures>,
    /// The most heap bytes live at once from the set-up to the last stroke: the mesh, the
    /// grid, the scratch and the strokes' own (`None` where the program does not count).
    pub peak_heap_bytes: Option<usize>,
    pub intersections: usize,
    /// Share of the edges at vertices the strokes moved or made (the remeshed regions) with
    /// length in [4/5·L, 4/3·L].
    pub edge_band_fraction: f64,
    pub valid: bool,
    pub faces_after: usize,
    /// What remeshing did over the run.
    pub remesh: RemeshReport,
    /// Smallest angle of the faces in the worked region, before the strokes and after.
    pub min_angle_before: AngleSummary,
    pub min_angle_after: AngleSummary,
    /// One-time set-up before the first stroke (grid build, collision set-up), not in the
    /// per-sample figures.
    pub setup_ms: f64,
    /// Moves shortened by the proximity test, and undone by the exact backstop.
    pub collisions: usize,
    pub reverted: usize,
    pub moves: usize,
    pub validation_error: Option<String>,
    /// GPU backends: how often the mesh was sent to the GPU whole, and how often patched after
    /// remeshing.
    pub gpu_uploads: Option<Uploads>,
    /// GPU backends: how many steps' backstop pairs the GPU filtered, how many pairs it left
    /// the CPU, and how many steps overflowed its room.
    pub gpu_backstop: Option<BackstopFilter>,
    /// GPU backends: the most GPU memory they held after any stroke.
    pub gpu_memory: Option<GpuMemory>,
    /// GPU backends: submissions and blocking read-backs over the strokes, per sample, per
    /// stroke and per `add_samples` call: what a stroke costs in round trips, whatever the
    /// adapter's speed.
    pub gpu_calls: Option<GpuCalls>,
}

/// What the topology changes of a fuse run did and cost.
#[derive(Debug, Clone, Serialize)]
pub struct TopologyFigures {
    pub joins: usize,
    pub splits: usize,
    pub refused: usize,
    /// The refusals by reason (`topology::Refusal`, snake case).
    pub refused_by_reason: std::collections::BTreeMap<String, usize>,
    pub joins_per_stroke: f64,
    pub splits_per_stroke: f64,
    pub ms: f64,
    pub ms_per_stroke: f64,
    /// The topology pass's time over the strokes' whole time (the phases and it).
    pub share: f64,
}

impl TopologyFigures {
    fn of(report: &TopologyReport, phases: &PhaseTimes, strokes: usize) -> TopologyFigures {
        let per_stroke = |n: f64| n / strokes.max(1) as f64;
        TopologyFigures {
            joins: report.joins,
            splits: report.splits,
            refused: report.refused.len(),
            refused_by_reason: report
                .refused
                .iter()
                .fold(Default::default(), |mut m, why| {
                    *m.entry(why.name().to_string()).or_default() += 1;
                    m
                }),
            joins_per_stroke: per_stroke(report.joins as f64),
            splits_per_stroke: per_stroke(report.splits as f64),
            ms: report.millis,
            ms_per_stroke: per_stroke(report.millis),
            share: report.millis / (phases.total() + report.millis).max(f64::MIN_POSITIVE),
        }
    }
}

/// Round trips to the GPU over a run of strokes (set-up before the first excluded).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct GpuCalls {
    /// Samples given per `add_samples` call (`None`: each stroke's samples in one call, the
    /// batch).
    pub samples_per_call: Option<usize>,
    pub calls: usize,
    pub submissions: usize,
    pub read_backs: usize,
    pub submissions_per_sample: f64,
    pub read_backs_per_sample: f64,
    pub read_backs_per_stroke: f64,
    pub read_backs_per_call: f64,
    /// Milliseconds per sample the CPU spent submitting, and blocked waiting for the GPU.
    pub submit_ms_per_sample: f64,
    pub waited_ms_per_sample: f64,
    /// Samples and steps recorded in runs ahead that the GPU's gate stopped, and the share of
    /// samples that is.
    pub gate_stops: usize,
    pub gate_stops_per_sample: f64,
    /// Why the gate stopped them, per reason.
    pub gate_stops_by: GateStops,
    /// Samples and steps taken from runs ahead.
    pub samples_ahead: usize,
    pub steps_ahead: usize,
    /// Samples of two steps whose steps a run recorded after their start, so that the gate
    /// did not stop it there.
    pub split_ahead: usize,
}

impl GpuCalls {
    /// The figures between two readings of a backend's uploads.
    fn between(
        before: Uploads,
        after: Uploads,
        (samples, strokes, calls): (usize, usize, usize),
    ) -> GpuCalls {
        let per = |count: usize, over: usize| count as f64 / over.max(1) as f64;
        let micros_per = |micros: u64, over: usize| micros as f64 / 1000.0 / over.max(1) as f64;
        let submissions = after.submissions - before.submissions;
        let read_backs = after.read_backs - before.read_backs;
        let gate_stops = after.gated_ahead - before.gated_ahead;
        GpuCalls {
            samples_per_call: None,
            calls,
            submissions,
            read_backs,
            submissions_per_sample: per(submissions, samples),
            read_backs_per_sample: per(read_backs, samples),
            read_backs_per_stroke: per(read_backs, strokes),
            read_backs_per_call: per(read_backs, calls),
            submit_ms_per_sample: micros_per(after.submit_micros - before.submit_micros, samples),
            waited_ms_per_sample: micros_per(after.waited_micros - before.waited_micros, samples),
            gate_stops,
            gate_stops_per_sample: per(gate_stops, samples),
            gate_stops_by: after.gate_stops.since(before.gate_stops),
            samples_ahead: after.samples_ahead - before.samples_ahead,
            steps_ahead: after.steps_ahead - before.steps_ahead,
            split_ahead: after.split_ahead - before.split_ahead,
        }
    }
}

/// How the bench hands strokes to the engine.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Feed {
    /// Samples per `add_samples` call (`None`: a stroke's samples and its end in one call,
    /// the batch).
    pub samples_per_call: Option<usize>,
    /// Every layer a stroke brushes fuses (`--policy fuse`, `crate::topology`).
    pub fuse: bool,
}

/// Runs `stroke` on `mesh` as an app would feed it: `feed.samples_per_call` samples per
/// `add_samples` call, then `finish` (`None`: all of them and the end in one call, as
/// [`Pipeline::apply_stroke`]). Returns the stroke's report and the calls it took.
pub fn feed_stroke(
    pipeline: &mut Pipeline,
    mesh: &mut Mesh,
    stroke: &Stroke,
    feed: Feed,
) -> Result<(StrokeReport, usize), PipelineError> {
    let settings = StrokeSettings {
        fuse: if feed.fuse {
            stroke.layers.clone()
        } else {
            Vec::new()
        },
        ..stroke.settings()
    };
    let mut in_progress = pipeline.begin_stroke(mesh, settings)?;
    let Some(chunk) = feed.samples_per_call else {
        return Ok((in_progress.finish_with(&stroke.samples)?, 1));
    };
    for samples in stroke.samples.chunks(chunk.max(1)) {
        in_progress.add_samples(samples)?;
    }
    // `finish` runs the last sample: a call too.
    let calls = stroke.samples.len().div_ceil(chunk.max(1)) + 1;
    Ok((in_progress.finish()?, calls))
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
    /// The most heap held while sculpting ([`SceneResult::peak_heap_bytes`]).
    pub peak_heap_bytes: Option<usize>,
    /// GPU backends: the most GPU memory they held after any stroke.
    pub gpu_memory: Option<GpuMemory>,
}

/// Runs `strokes` on `mesh` and measures. `progress` is told after each stroke.
pub fn run_strokes(
    name: &str,
    mesh: &mut Mesh,
    strokes: &[Stroke],
    pipeline: &mut Pipeline,
    mut progress: impl FnMut(usize),
    (check_intersections, feed): (bool, Feed),
) -> Result<SceneResult, PipelineError> {
    let samples_per_call = feed.samples_per_call;
    let (vertices, faces) = (mesh.live_vertex_count(), mesh.live_face_count());
    crate::memory::reset_peak();
    // Where the strokes went: vertices that moved or were made; the edge band is measured there.
    let start_positions = mesh.positions().to_vec();
    let start_faces = mesh.faces().to_vec();
    // The bench's own copies, left out of the engine's peak below.
    let copies = std::mem::size_of_val(start_positions.as_slice())
        + std::mem::size_of_val(start_faces.as_slice());
    let mean_edge_length = mesh.edge_length_stats().mean;
    let started = std::time::Instant::now();
    pipeline.prepare(mesh)?;
    let setup_ms = started.elapsed().as_secs_f64() * 1e3;
    let mut phases = PhaseTimes::default();
    let mut remesh = RemeshReport::default();
    let mut topology = TopologyReport::default();
    let (mut samples, mut steps, mut collisions, mut reverted, mut moves) = (0, 0, 0, 0, 0);
    let mut gpu_memory = pipeline.gpu_memory(mesh);
    let uploads_before = pipeline.uploads();
    let mut calls = 0;
    for (i, stroke) in strokes.iter().enumerate() {
        let (report, stroke_calls) = feed_stroke(pipeline, mesh, stroke, feed)?;
        topology.add(&report.topology);
        calls += stroke_calls;
        gpu_memory = gpu_memory
            .into_iter()
            .chain(pipeline.gpu_memory(mesh))
            .reduce(GpuMemory::max);
        phases.add(&report.phases);
        samples += report.samples;
        steps += report.steps;
        collisions += report.clamped;
        reverted += report.reverted;
        moves += report.moves;
        remesh.add(&report.remesh);
        progress(i + 1);
    }
    // The most heap the mesh, the set-up and the strokes held at once (`None` unless the
    // program counts, as `slayer` does).
    let peak_heap_bytes = crate::memory::peak_bytes().map(|p| p.saturating_sub(copies));
    let sampling_ms = phases.total() - phases.remesh;
    let gpu_calls = uploads_before
        .zip(pipeline.uploads())
        .map(|(before, after)| GpuCalls {
            samples_per_call,
            ..GpuCalls::between(before, after, (samples, strokes.len(), calls))
        });
    let validation = mesh.validate();
    let intersections = if check_intersections {
        find_intersections(mesh).total()
    } else {
        0
    };
    let worked = |v: u32| {
        start_positions
            .get(v as usize)
            .is_none_or(|&p| p != mesh.positions()[v as usize])
    };
    let band = edge_band_fraction_where(mesh, mean_edge_length, |a, b| worked(a) || worked(b));
    let min_angle_before = AngleSummary::of(
        start_faces
            .iter()
            .filter(|f| f[0] != crate::mesh::INVALID && f.iter().any(|&v| worked(v)))
            .map(|f| f.map(|v| start_positions[v as usize])),
    );
    let min_angle_after = AngleSummary::of(
        (0..mesh.face_count())
            .filter(|&f| !mesh.is_face_dead(f) && mesh.faces()[f].iter().any(|&v| worked(v)))
            .map(|f| mesh.face_positions(f)),
    );
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
        topology: feed
            .fuse
            .then(|| TopologyFigures::of(&topology, &phases, strokes.len())),
        intersections,
        edge_band_fraction: band,
        valid: validation.is_ok(),
        validation_error: validation.err().map(|e| e.to_string()),
        faces_after: mesh.live_face_count(),
        remesh,
        min_angle_before,
        min_angle_after,
        setup_ms,
        peak_heap_bytes,
        collisions,
        reverted,
        moves,
        gpu_uploads: pipeline.uploads(),
        gpu_backstop: pipeline.backstop_filter(),
        gpu_memory,
        gpu_calls,
    })
}

/// Share of edges with length in [4/5·L, 4/3·L] (the remesher's band).
pub fn edge_band_fraction(mesh: &Mesh, edge: f64) -> f64 {
    edge_band_fraction_where(mesh, edge, |_, _| true)
}

/// Share of the edges `(a, b)` picked by `counts` with length in [4/5·L, 4/3·L]; 1 when none is
/// picked.
pub fn edge_band_fraction_where(mesh: &Mesh, edge: f64, counts: impl Fn(u32, u32) -> bool) -> f64 {
    let (lo, hi) = (0.8 * edge, 4.0 / 3.0 * edge);
    let mut inside = 0usize;
    let mut total = 0usize;
    mesh.for_each_edge(|a, b| {
        if !counts(a, b) {
            return;
        }
        let l = mesh.positions()[a as usize].distance(mesh.positions()[b as usize]) as f64;
        total += 1;
        if (lo..=hi).contains(&l) {
            inside += 1;
        }
    });
    if total == 0 {
        return 1.0;
    }
    inside as f64 / total as f64
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
