//! `slayer remesh`: a whole mesh to a new resolution, with its quality before and after and
//! its distance to the input.

use std::path::Path;
use std::process::ExitCode;

use anyhow::bail;
use serde::Serialize;
use slayer::mesh::Mesh;
use slayer::remesh::{
    Culling, Distance, Quality, RemeshReport, RemeshSettings, Surface, remesh_all_with,
};

use crate::progress::Steps;

/// Largest mesh a whole-mesh remesh may produce.
const MAX_FACES: usize = 50_000_000;

/// What the new resolution is given by.
#[derive(Debug, Clone, Copy)]
pub enum Target {
    /// The mesh's own mean edge length: an even mesh at the same resolution.
    MeanEdge,
    Edge(f32),
    /// About this many faces.
    Faces(u64),
    /// The mean edge length times this.
    Scale(f32),
}

/// Everything `--json` prints.
#[derive(Debug, Serialize)]
struct Summary {
    input: String,
    output: String,
    target_edge: f32,
    threads: usize,
    before: Quality,
    after: Quality,
    /// From the result to the input, in target edge lengths.
    distance_to_input: Distance,
    remesh: RemeshReport,
}

/// Remeshes a whole mesh toward the edge length `target` asks for and reports how even the
/// result is and how far it lies from the input.
pub fn run(
    input: &Path,
    target: Target,
    (output, json): (&Path, bool),
    strict: bool,
) -> anyhow::Result<ExitCode> {
    slayer::io::Format::of_path(output)?;
    let steps = Steps::new("remesh");
    steps.step("reading");
    let mut mesh = crate::open::open(input, strict)?.into_mesh();
    let edge = target_edge(&mesh, target)?;
    steps.step("measuring the input");
    let before = Quality::of(&mesh);
    let surface = Surface::of(&mesh);
    let mut settings = RemeshSettings::new(edge);
    settings.exclusion_ring = slayer::collide::neighbourhood::exclusion_ring(&mesh, edge);
    steps.step("remeshing");
    let report = remesh_all_with(&mut mesh, &settings, Culling::On, &mut |at| {
        // Every 32nd cell: thousands of cells, each a few milliseconds.
        if at.cell % 32 == 0 || at.cell == at.cells {
            let (round, rounds, cell, cells) = (at.round, at.rounds, at.cell, at.cells);
            steps.step(&format!(
                "remeshing, round {round} of {rounds}: cell {cell} of {cells}"
            ));
        }
    })?;
    mesh.validate()?;
    steps.step("measuring the result");
    let summary = Summary {
        input: input.display().to_string(),
        output: output.display().to_string(),
        target_edge: edge,
        threads: rayon::current_num_threads(),
        before,
        after: Quality::of(&mesh),
        distance_to_input: surface.distance_of(&mesh, edge),
        remesh: report,
    };
    steps.step("writing");
    slayer::io::write_mesh(&mesh, output)?;
    steps.finish();
    if json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        print_summary(&summary);
    }
    Ok(ExitCode::SUCCESS)
}

/// The edge length `target` names, checked: a positive length whose mesh fits in memory.
fn target_edge(mesh: &Mesh, target: Target) -> anyhow::Result<f32> {
    let mean = mesh.mean_edge_length();
    let edge = match target {
        Target::MeanEdge => mean,
        Target::Edge(edge) => edge,
        Target::Scale(scale) => {
            if !(scale.is_finite() && scale > 0.0) {
                bail!("--scale {scale} is not a positive factor");
            }
            scale * mean
        }
        Target::Faces(faces) => {
            if faces == 0 {
                bail!("--faces 0: give a positive face count");
            }
            // Equilateral triangles of edge L cover √3/4·L² each.
            (4.0 * area(mesh) / (3f64.sqrt() * faces as f64)).sqrt() as f32
        }
    };
    if !(edge.is_finite() && edge > 0.0) {
        bail!("the target edge length {edge} is not a positive length");
    }
    // Faces scale with (mean / L)²: refuse what would not fit in memory rather than try.
    let faces = mesh.live_face_count();
    let expected = faces as f64 * (mean as f64 / edge as f64).powi(2);
    if expected > MAX_FACES as f64 {
        bail!(
            "an edge length of {edge} would make about {expected:.0} faces from {faces} (mean edge {mean:.6}); the limit is {MAX_FACES}"
        );
    }
    Ok(edge)
}

/// The live faces' total area.
fn area(mesh: &Mesh) -> f64 {
    (0..mesh.face_count())
        .filter(|&f| !mesh.is_face_dead(f))
        .map(|f| {
            let [a, b, c] = mesh.face_positions(f).map(|p| p.as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

fn print_summary(s: &Summary) {
    let (before, after, report) = (&s.before, &s.after, &s.remesh);
    let threads = match s.threads {
        1 => "1 thread".to_string(),
        n => format!("{n} threads"),
    };
    let subdivided = match report.subdivisions {
        0 => String::new(),
        n => format!("{n} levels of subdivision, then "),
    };
    println!(
        "remeshed to L = {}: edge cv {:.3} -> {:.3}, {} -> {} faces ({subdivided}{} splits, {} collapses, {} flips, {} relaxed; {} refused to keep the shape) in {:.0} ms on {threads} -> {}",
        s.target_edge,
        before.edge_cv,
        after.edge_cv,
        before.faces,
        after.faces,
        report.splits,
        report.collapses,
        report.flips,
        report.relaxed,
        report.shape_refused,
        report.millis,
        s.output
    );
    let (a, b) = (&before.smallest_angle, &after.smallest_angle);
    println!(
        "smallest angle per face: p1 {:.1}° -> {:.1}°, p5 {:.1}° -> {:.1}°, median {:.1}° -> {:.1}°, below 30° {:.2} % -> {:.2} %",
        a.p1,
        b.p1,
        a.p5,
        b.p5,
        a.median,
        b.median,
        100.0 * a.below_30,
        100.0 * b.below_30,
    );
    println!(
        "valence of interior vertices: 6 {:.1} % -> {:.1} %; after: {}",
        100.0 * before.valence_6,
        100.0 * after.valence_6,
        valence_line(after)
    );
    let d = &s.distance_to_input;
    println!(
        "distance to the input: max {:.4} L, mean {:.4} L over {} points (vertices and face centroids)",
        d.max, d.mean, d.samples
    );
}

/// `5: 3.1 %, 6: 92.0 %, 7: 3.0 %, ≥12: 0.1 %`: each valence's share of the interior vertices.
fn valence_line(quality: &Quality) -> String {
    let total: usize = quality.valences.iter().map(|&(_, n)| n).sum();
    let last = slayer::remesh::VALENCE_BUCKETS;
    quality
        .valences
        .iter()
        .map(|&(valence, n)| {
            let label = if valence == last {
                format!("≥{last}")
            } else {
                valence.to_string()
            };
            format!("{label}: {:.1} %", 100.0 * n as f64 / total.max(1) as f64)
        })
        .collect::<Vec<_>>()
        .join(", ")
}
