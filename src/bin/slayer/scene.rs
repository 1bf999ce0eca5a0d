use std::path::Path;
use std::process::ExitCode;

use anyhow::Context;
use slayer::scene::{SceneKind, SceneSpec, generate};

use crate::progress::Steps;

pub fn run(
    name: &str,
    triangles: Option<usize>,
    seed: u64,
    jitter: f32,
    output: &Path,
) -> anyhow::Result<ExitCode> {
    let kind: SceneKind = name.parse()?;
    let spec = SceneSpec {
        kind,
        triangles: triangles.unwrap_or(kind.default_triangles()),
        seed,
    };
    slayer::session::check_save_path(output)?;
    if !(0.0..=slayer::scene::MAX_JITTER).contains(&jitter) {
        anyhow::bail!(
            "--jitter {jitter} is out of range (0 to {} edge lengths)",
            slayer::scene::MAX_JITTER
        );
    }
    let steps = Steps::new(kind.name());
    steps.step(&format!("generating {} triangles", spec.triangles));
    let mut mesh = generate(&spec)?;
    if jitter > 0.0 {
        steps.step(&format!("jittering vertices by up to {jitter} L"));
        slayer::scene::jitter(&mut mesh, jitter, seed).map_err(anyhow::Error::msg)?;
    }
    steps.step(&format!("writing {}", output.display()));
    let session = slayer::session::Session::new(mesh);
    slayer::session::save(&session, output, true).context("writing the scene")?;
    let mesh = session.mesh();
    let seconds = steps.finish();
    println!(
        "{}: {} layers, {} vertices, {} faces, mean edge {:.6} -> {} ({seconds:.1} s)",
        kind,
        mesh.layer_count(),
        mesh.live_vertex_count(),
        mesh.live_face_count(),
        mesh.mean_edge_length(),
        output.display()
    );
    Ok(ExitCode::SUCCESS)
}
