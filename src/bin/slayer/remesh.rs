use std::path::Path;
use std::process::ExitCode;

use slayer::bench::AngleSummary;
use slayer::remesh::{RemeshSettings, remesh_all};

/// Largest mesh a whole-mesh remesh may produce.
const MAX_FACES: usize = 50_000_000;

/// Remeshes a whole mesh toward edge length `edge` (the mesh's mean edge length by default).
pub fn run(
    input: &Path,
    edge: Option<f32>,
    output: &Path,
    strict: bool,
) -> anyhow::Result<ExitCode> {
    slayer::io::Format::of_path(output)?;
    let mut mesh = crate::open::open(input, strict)?.into_mesh();
    let before = mesh.edge_length_stats();
    let edge = edge.unwrap_or(before.mean as f32);
    if !(edge.is_finite() && edge > 0.0) {
        anyhow::bail!("--edge {edge} is not a positive length");
    }
    // Faces scale with (mean / L)²: refuse what would not fit in memory rather than try.
    let faces_before = mesh.live_face_count();
    let expected = faces_before as f64 * (before.mean / edge as f64).powi(2);
    if expected > MAX_FACES as f64 {
        anyhow::bail!(
            "--edge {edge} would make about {expected:.0} faces from {faces_before} (mean edge {:.6}); the limit is {MAX_FACES}",
            before.mean
        );
    }
    let mut settings = RemeshSettings::new(edge);
    settings.exclusion_ring = slayer::collide::neighbourhood::exclusion_ring(&mesh, edge);
    let angles_before = min_angles(&mesh);
    let report = remesh_all(&mut mesh, &settings)?;
    mesh.validate()?;
    let after = mesh.edge_length_stats();
    slayer::io::write_mesh(&mesh, output)?;
    println!(
        "remeshed to L = {edge}: edge cv {:.3} -> {:.3}, {} -> {} faces ({} splits, {} collapses, {} flips, {} relaxed; {} refused to keep the shape) in {:.0} ms -> {}",
        before.coefficient_of_variation(),
        after.coefficient_of_variation(),
        faces_before,
        mesh.live_face_count(),
        report.splits,
        report.collapses,
        report.flips,
        report.relaxed,
        report.shape_refused,
        report.millis,
        output.display()
    );
    let angles_after = min_angles(&mesh);
    println!(
        "smallest angle per face: p1 {:.1}° -> {:.1}°, p5 {:.1}° -> {:.1}°, median {:.1}° -> {:.1}°, below 30° {:.2} % -> {:.2} %",
        angles_before.p1,
        angles_after.p1,
        angles_before.p5,
        angles_after.p5,
        angles_before.median,
        angles_after.median,
        100.0 * angles_before.below_30,
        100.0 * angles_after.below_30,
    );
    Ok(ExitCode::SUCCESS)
}

fn min_angles(mesh: &slayer::mesh::Mesh) -> AngleSummary {
    AngleSummary::of(
        (0..mesh.face_count())
            .filter(|&f| !mesh.is_face_dead(f))
            .map(|f| mesh.face_positions(f)),
    )
}
