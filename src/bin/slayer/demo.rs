use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use slayer::bench::{ScriptSpec, generate_script, paper_table};
use slayer::pipeline::{CpuPipeline, PipelineSettings, SculptPipeline};
use slayer::scene::{SceneKind, SceneSpec, generate};

use crate::progress::Steps;

/// Strokes in the demo's script: enough to see every brush of the bench mix at work.
const DEMO_STROKES: usize = 12;

/// Generates the default material (peeling plaster), sculpts it with a short seeded stroke
/// script, writes the material before and after, checks the result and prints the timings.
pub fn run(out: &Path, triangles: usize) -> anyhow::Result<ExitCode> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let spec = SceneSpec {
        triangles,
        ..SceneSpec::new(SceneKind::Plaster)
    };
    println!(
        "slayer demo: default material `{}` with {} triangles",
        spec.kind, spec.triangles
    );
    let started = Instant::now();
    let steps = Steps::new("demo");
    steps.step("generating");
    let mut mesh = generate(&spec)?;
    let before = out.join("plaster.ply");
    steps.step(&format!("writing {}", before.display()));
    slayer::io::write_mesh(&mesh, &before)?;
    let script = generate_script(
        &mesh,
        &ScriptSpec {
            strokes: DEMO_STROKES,
            ..ScriptSpec::default()
        },
    );
    let strokes_path = out.join("strokes.json");
    slayer::io::write_atomically(&strokes_path, script.to_json().as_bytes())?;
    let strokes = script.resolve(&mesh, &strokes_path.display().to_string())?;
    steps.finish();
    println!(
        "  generated {} layers, {} vertices, {} faces in {:.1} s -> {}",
        mesh.layer_count(),
        mesh.live_vertex_count(),
        mesh.live_face_count(),
        started.elapsed().as_secs_f64(),
        before.display()
    );

    let mut pipeline = CpuPipeline::new(PipelineSettings::default());
    println!(
        "  sculpting {} strokes ({}) on the {} backend -> {}",
        strokes.len(),
        strokes
            .iter()
            .map(|s| s.brush.kind.name())
            .collect::<Vec<_>>()
            .join(", "),
        pipeline.name(),
        strokes_path.display()
    );
    let result = crate::bench::sculpt_with_progress("plaster", &mut mesh, &strokes, &mut pipeline)?;
    println!("{}", paper_table(std::slice::from_ref(&result)));

    let after = out.join("plaster-sculpted.ply");
    let after_obj = out.join("plaster-sculpted.obj");
    slayer::io::write_mesh(&mesh, &after)?;
    slayer::io::write_mesh(&mesh, &after_obj)?;
    println!("  wrote {} and {}", after.display(), after_obj.display());
    let report = crate::check::report(&after)?;
    println!("{report}");
    Ok(if report.is_clean() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
