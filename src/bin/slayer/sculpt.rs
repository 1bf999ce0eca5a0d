use std::path::Path;
use std::process::ExitCode;

use anyhow::Context;
use slayer::brush::StrokeFile;
use slayer::pipeline::{PipelineSettings, Remeshing, StrokeReport};

use crate::progress::Bar;

/// Applies a stroke file to a mesh or session and writes the result; the input is never
/// touched. Each stroke is one history entry of the session a `.slayer` output keeps.
pub fn run(
    input: &Path,
    strokes: &Path,
    output: &Path,
    stats: Option<&Path>,
    remeshing: Remeshing,
    backend: crate::backend::Backend,
) -> anyhow::Result<ExitCode> {
    slayer::session::check_save_path(output)?;
    let mut session = slayer::session::open(input)?;
    let text =
        std::fs::read_to_string(strokes).with_context(|| format!("{}", strokes.display()))?;
    let name = strokes.display().to_string();
    let file = StrokeFile::parse(&text, &name)?;
    let strokes = file.resolve(session.mesh(), &name)?;
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
        let (report, recorded) = session.apply_stroke(&mut pipeline, stroke)?;
        if recorded.dropped > 0 {
            bar.println(&format!(
                "note: the history passed its cap of {} MiB; its {} oldest entries were dropped",
                session.history().cap_bytes() >> 20,
                recorded.dropped
            ));
        }
        reports.push(report);
        bar.inc();
    }
    bar.finish();
    if let Some(why) = pipeline.kernel_failure() {
        eprintln!("warning: the GPU failed ({why}); the strokes finished on the CPU");
    }
    let mesh = session.mesh();
    mesh.validate()
        .context("the sculpted mesh failed validation (not written)")?;
    slayer::session::save(&session, output, true)?;
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
