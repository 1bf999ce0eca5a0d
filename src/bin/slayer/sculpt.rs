use std::path::Path;
use std::process::ExitCode;

use anyhow::Context;
use slayer::brush::StrokeFile;
use slayer::pipeline::{PipelineSettings, Remeshing, StrokeReport};

use crate::progress::Bar;

/// Applies a stroke file to a mesh and writes the result; the input is never touched.
pub fn run(
    input: &Path,
    strokes: &Path,
    output: &Path,
    stats: Option<&Path>,
    remeshing: Remeshing,
    backend: crate::backend::Backend,
) -> anyhow::Result<ExitCode> {
    slayer::io::Format::of_path(output)?;
    let mut mesh = slayer::io::read_mesh(input)?;
    let text =
        std::fs::read_to_string(strokes).with_context(|| format!("{}", strokes.display()))?;
    let name = strokes.display().to_string();
    let file = StrokeFile::parse(&text, &name)?;
    let strokes = file.resolve(&mesh, &name)?;
    let mut pipeline = crate::backend::choose(
        backend,
        PipelineSettings {
            remeshing,
            ..PipelineSettings::default()
        },
    )?
    .pipeline;
    let bar = Bar::new("sculpt", strokes.len() as u64);
    let mut reports: Vec<StrokeReport> = Vec::with_capacity(strokes.len());
    for stroke in &strokes {
        reports.push(pipeline.apply_stroke(&mut mesh, stroke)?);
        bar.inc();
    }
    bar.finish();
    if let Some(why) = pipeline.kernel_failure() {
        eprintln!("warning: the GPU failed ({why}); the strokes finished on the CPU");
    }
    mesh.validate()
        .context("the sculpted mesh failed validation (not written)")?;
    slayer::io::write_mesh(&mesh, output)?;
    let samples: usize = reports.iter().map(|r| r.samples).sum();
    let clamped: usize = reports.iter().map(|r| r.clamped).sum();
    let total_ms: f64 = reports.iter().map(|r| r.phases.total()).sum();
    println!(
        "{} strokes, {samples} samples, {clamped} collisions, {:.3} ms per sample -> {}",
        strokes.len(),
        total_ms / samples.max(1) as f64,
        output.display()
    );
    if let Some(path) = stats {
        let json = serde_json::json!({
            "backend": pipeline.name(),
            "strokes": reports,
            "vertices": mesh.live_vertex_count(),
            "faces": mesh.live_face_count(),
        });
        slayer::io::write_atomically(path, serde_json::to_string_pretty(&json)?.as_bytes())?;
    }
    Ok(ExitCode::SUCCESS)
}
