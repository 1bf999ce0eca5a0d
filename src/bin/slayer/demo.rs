use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use slayer::scene::{SceneKind, SceneSpec, generate};

use crate::progress::Steps;

/// Generates the default material (peeling plaster), writes it and checks the written file.
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
    let mesh = generate(&spec)?;
    let path = out.join("plaster.ply");
    steps.step(&format!("writing {}", path.display()));
    slayer::io::write_mesh(&mesh, &path)?;
    let obj = out.join("plaster.obj");
    steps.step(&format!("writing {}", obj.display()));
    slayer::io::write_mesh(&mesh, &obj)?;
    steps.finish();
    println!(
        "  generated {} layers, {} vertices, {} faces in {:.1} s",
        mesh.layer_count(),
        mesh.live_vertex_count(),
        mesh.live_face_count(),
        started.elapsed().as_secs_f64()
    );
    println!("  wrote {} and {}", path.display(), obj.display());
    let report = crate::check::report(&path)?;
    println!("{report}");
    Ok(if report.is_clean() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
