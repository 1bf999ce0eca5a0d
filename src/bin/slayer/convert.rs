//! `slayer convert IN OUT`: a mesh or session from one format to another (OBJ, PLY, STL,
//! `.slayer`), by extension, optionally only some layers.

use std::path::Path;
use std::process::ExitCode;

use anyhow::Context;

/// Reads `input` (repaired unless `strict`) and writes `output`, keeping `layers` (names or
/// numbers; all when empty).
pub fn run(
    input: &Path,
    output: &Path,
    layers: &[String],
    strict: bool,
) -> anyhow::Result<ExitCode> {
    slayer::session::check_save_path(output)?;
    let mut session = crate::open::open(input, strict)?;
    if !layers.is_empty() {
        let chosen = crate::render::resolve_layers(session.mesh(), layers)?;
        let mesh = session.mesh().with_layers(&chosen)?;
        session = slayer::session::Session::new(mesh);
    }
    slayer::session::save(&session, output, true)
        .with_context(|| format!("writing {}", output.display()))?;
    let mesh = session.mesh();
    println!(
        "{} -> {}: {} vertices, {} faces, {} layers",
        input.display(),
        output.display(),
        mesh.live_vertex_count(),
        mesh.live_face_count(),
        mesh.layer_count()
    );
    Ok(ExitCode::SUCCESS)
}
