use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use slayer::bench::{
    ScalingRow, SceneResult, ScriptSpec, generate_script, paper_table, run_strokes, scaling_svg,
    scaling_table,
};
use slayer::pipeline::{CpuPipeline, PipelineSettings, Remeshing, SculptPipeline};
use slayer::scene::{SceneKind, SceneSpec, generate};

use crate::progress::{Bar, Steps};

pub struct Options {
    pub scenes: Vec<SceneKind>,
    pub triangles: Option<usize>,
    pub strokes: usize,
    pub seed: u64,
    pub json: Option<PathBuf>,
    pub scaling: bool,
    pub scaling_sizes: Vec<usize>,
    pub backend: String,
    /// When the touched region is remeshed.
    pub remeshing: Remeshing,
}

/// `--scene`: one scene name, `all` (the paper's three materials) or `none` (scaling only).
pub fn parse_scenes(scene: &str) -> Result<Vec<SceneKind>, slayer::scene::SceneError> {
    Ok(match scene {
        "all" => vec![SceneKind::Plaster, SceneKind::Bark, SceneKind::Metal],
        "none" => Vec::new(),
        name => vec![name.parse()?],
    })
}

fn bench_scene(
    kind: SceneKind,
    triangles: usize,
    strokes: usize,
    seed: u64,
    remeshing: Remeshing,
) -> anyhow::Result<SceneResult> {
    let steps = Steps::new(kind.name());
    steps.step(&format!("generating {triangles} triangles"));
    let mut mesh = generate(&SceneSpec {
        kind,
        triangles,
        seed,
    })?;
    steps.step("writing the stroke script");
    let script = generate_script(
        &mesh,
        &ScriptSpec {
            strokes,
            seed,
            ..ScriptSpec::default()
        },
    );
    let strokes = script.resolve(&mesh, "generated script")?;
    steps.finish();
    let mut pipeline = CpuPipeline::new(PipelineSettings {
        remeshing,
        ..PipelineSettings::default()
    });
    sculpt_with_progress(kind.name(), &mut mesh, &strokes, &mut pipeline)
}

/// Runs `strokes` through `pipeline` with a progress bar, measuring as the bench does.
pub fn sculpt_with_progress(
    name: &str,
    mesh: &mut slayer::mesh::Mesh,
    strokes: &[slayer::brush::Stroke],
    pipeline: &mut dyn SculptPipeline,
) -> anyhow::Result<SceneResult> {
    let bar = Bar::new(name, strokes.len() as u64);
    let result = run_strokes(name, mesh, strokes, pipeline, |_| bar.inc(), true)?;
    bar.finish();
    Ok(result)
}

pub fn run(options: &Options) -> anyhow::Result<ExitCode> {
    if options.backend != "cpu" {
        anyhow::bail!(
            "backend `{}` is not available yet (only `cpu`)",
            options.backend
        );
    }
    let pipeline_name = CpuPipeline::new(PipelineSettings::default()).name();
    let mut scenes = Vec::new();
    for &kind in &options.scenes {
        let triangles = options.triangles.unwrap_or(kind.default_triangles());
        scenes.push(bench_scene(
            kind,
            triangles,
            options.strokes,
            options.seed,
            options.remeshing,
        )?);
    }
    if !scenes.is_empty() {
        println!("{}", paper_table(&scenes));
    }
    let mut scaling = Vec::new();
    if options.scaling {
        for &faces in &options.scaling_sizes {
            let r = bench_scene(
                SceneKind::Plaster,
                faces,
                options.strokes.min(8),
                options.seed,
                options.remeshing,
            )?;
            scaling.push(ScalingRow {
                faces: r.faces,
                ms_per_sample: r.ms_per_sample,
                ms_per_remesh: r.ms_per_remesh,
                samples: r.samples,
                steps: r.steps,
                moves: r.moves,
            });
        }
        println!("scaling: the same strokes (radius 12 L) on plaster of growing size");
        println!("{}", scaling_table(&scaling));
    }
    let clean = scenes.iter().all(|s| s.valid && s.intersections == 0);
    if let Some(path) = &options.json {
        let json = serde_json::json!({
            "backend": pipeline_name,
            "adapter": "none (CPU)",
            "threads": rayon::current_num_threads(),
            "revision": slayer::bench::git_revision(),
            "scenes": scenes,
            "scaling": if options.scaling { Some(&scaling) } else { None },
        });
        slayer::io::write_atomically(path, serde_json::to_string_pretty(&json)?.as_bytes())?;
        if options.scaling {
            let svg = path.with_extension("scaling.svg");
            write_svg(&svg, &scaling)?;
        }
    } else if options.scaling {
        write_svg(Path::new("scaling.svg"), &scaling)?;
    }
    if !clean {
        eprintln!("error: a scene ended with intersections or an invalid mesh");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

fn write_svg(path: &Path, rows: &[ScalingRow]) -> anyhow::Result<()> {
    let svg = scaling_svg(rows, "slayer: ms per stroke sample against mesh size (CPU)");
    slayer::io::write_atomically(path, svg.as_bytes()).context("writing the scaling plot")?;
    println!("scaling plot: {}", path.display());
    Ok(())
}
