use std::path::Path;
use std::process::ExitCode;

use slayer::bench::{BrushMix, ScriptSpec, generate_script};
use slayer::scene::{SceneKind, SceneSpec, generate};

/// Writes the bench's stroke script for a scene, so the same strokes replay anywhere.
pub fn run(
    scene: &str,
    triangles: Option<usize>,
    strokes: usize,
    seed: u64,
    torture: bool,
    output: &Path,
) -> anyhow::Result<ExitCode> {
    check_stroke_count("--count", strokes)?;
    let kind: SceneKind = scene.parse()?;
    let mesh = generate(&SceneSpec {
        kind,
        triangles: triangles.unwrap_or(kind.default_triangles()),
        seed,
    })?;
    let spec = ScriptSpec {
        strokes,
        seed,
        mix: if torture {
            BrushMix::Torture
        } else {
            BrushMix::for_scene(kind)
        },
        ..ScriptSpec::default()
    };
    let script = generate_script(&mesh, &spec);
    slayer::io::write_atomically(output, script.to_json().as_bytes())?;
    println!(
        "{} strokes for {kind} ({} faces, seed {seed}) -> {}",
        script.strokes.len(),
        mesh.live_face_count(),
        output.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// Refuses a stroke count that no stroke file may hold ([`slayer::brush::MAX_STROKES`]), before
/// anything is generated: a script of that many strokes could not be replayed.
pub fn check_stroke_count(flag: &str, count: usize) -> anyhow::Result<()> {
    let limit = slayer::brush::MAX_STROKES;
    if count > limit {
        anyhow::bail!(
            "{flag} {count} is more strokes than a stroke file may hold ({limit}); \
             run several scripts with different --seed values instead"
        );
    }
    Ok(())
}
