use std::path::Path;
use std::process::ExitCode;

use slayer::remesh::{RemeshSettings, remesh_all};

/// Remeshes a whole mesh toward edge length `edge` (the mesh's mean edge length by default).
pub fn run(input: &Path, edge: Option<f32>, output: &Path) -> anyhow::Result<ExitCode> {
    slayer::io::Format::of_path(output)?;
    let mut mesh = slayer::io::read_mesh(input)?;
    let before = mesh.edge_length_stats();
    let edge = edge.unwrap_or(before.mean as f32);
    if !(edge.is_finite() && edge > 0.0) {
        anyhow::bail!("--edge {edge} is not a positive length");
    }
    let mut settings = RemeshSettings::new(edge);
    settings.exclusion_ring = slayer::collide::neighbourhood::exclusion_ring(&mesh, edge);
    let report = remesh_all(&mut mesh, &settings)?;
    mesh.validate()?;
    let after = mesh.edge_length_stats();
    slayer::io::write_mesh(&mesh, output)?;
    println!(
        "remeshed to L = {edge}: edge cv {:.3} -> {:.3}, {} -> {} faces ({} splits, {} collapses, {} flips, {} relaxed) in {:.0} ms -> {}",
        before.coefficient_of_variation(),
        after.coefficient_of_variation(),
        before.edges,
        mesh.live_face_count(),
        report.splits,
        report.collapses,
        report.flips,
        report.relaxed,
        report.millis,
        output.display()
    );
    Ok(ExitCode::SUCCESS)
}
