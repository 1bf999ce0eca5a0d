use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use slayer::bench::{
    Feed, ScalingRow, SceneResult, ScriptSpec, generate_script, gpu_memory_lines, paper_table,
    run_strokes, scaling_svg, scaling_table, topology_lines,
};
use slayer::mesh::Mesh;
use slayer::pipeline::{PipelineSettings, Remeshing};
use slayer::scene::{SceneKind, SceneSpec, generate};
use slayer::topology::ProximityPolicy;

use crate::backend::{self, Backend};
use crate::progress::{Bar, Steps};

pub struct Options {
    pub scenes: Vec<SceneKind>,
    pub triangles: Option<usize>,
    pub strokes: usize,
    pub seed: u64,
    pub json: Option<PathBuf>,
    pub scaling: bool,
    pub scaling_sizes: Vec<usize>,
    pub backend: Backend,
    /// When the touched region is remeshed.
    pub remeshing: Remeshing,
    /// Samples per `add_samples` call (`None`: a stroke's samples in one call).
    pub samples_per_call: Option<usize>,
    /// Skip the collision searches that cannot find anything (`--no-cull` turns it off).
    pub cull: bool,
    /// Every brushed layer collides (the default) or fuses (`--policy fuse`).
    pub policy: ProximityPolicy,
}

impl Options {
    fn feed(&self) -> Feed {
        Feed {
            samples_per_call: self.samples_per_call,
            fuse: self.policy == ProximityPolicy::Fuse,
        }
    }
}

/// `--scene`: one scene name, `all` (the paper's three materials) or `none` (scaling only).
pub fn parse_scenes(scene: &str) -> Result<Vec<SceneKind>, slayer::scene::SceneError> {
    Ok(match scene {
        "all" => vec![SceneKind::Plaster, SceneKind::Bark, SceneKind::Metal],
        "none" => Vec::new(),
        name => vec![name.parse()?],
    })
}

/// One scene on one backend (or on both, compared).
struct SceneRun {
    result: SceneResult,
    /// With `--backend both`: the GPU's figures and how they compare.
    gpu: Option<(SceneResult, Parity)>,
}

/// How the GPU path's result compares with the CPU's on the same strokes.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Parity {
    /// Largest distance between a vertex on one path and the same vertex on the other;
    /// `None` when remeshing made the two topologies differ (then vertices do not correspond).
    pub max_position_deviation: Option<f64>,
    pub max_position_deviation_edges: Option<f64>,
    pub collision_count_cpu: usize,
    pub collision_count_gpu: usize,
    /// GPU time over CPU time per phase, from the same run.
    pub gpu_over_cpu: std::collections::BTreeMap<&'static str, f64>,
}

fn parity(cpu: (&SceneResult, &Mesh), gpu: (&SceneResult, &Mesh)) -> Parity {
    let same_topology = cpu.1.faces() == gpu.1.faces();
    let deviation = same_topology.then(|| {
        cpu.1
            .positions()
            .iter()
            .zip(gpu.1.positions())
            .map(|(a, b)| a.distance(*b) as f64)
            .fold(0.0, f64::max)
    });
    let mut ratios = std::collections::BTreeMap::new();
    for ((name, c), (_, g)) in cpu.0.phase_ms.named().iter().zip(gpu.0.phase_ms.named()) {
        if *c > 0.0 {
            ratios.insert(*name, g / c);
        }
    }
    Parity {
        max_position_deviation: deviation,
        max_position_deviation_edges: deviation.map(|d| d / cpu.0.mean_edge_length),
        collision_count_cpu: cpu.0.collisions,
        collision_count_gpu: gpu.0.collisions,
        gpu_over_cpu: ratios,
    }
}

fn bench_scene(
    kind: SceneKind,
    triangles: usize,
    strokes: usize,
    seed: u64,
    (remeshing, chosen, feed, cull): (Remeshing, Backend, Feed, bool),
) -> anyhow::Result<SceneRun> {
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
            mix: slayer::bench::BrushMix::for_scene(kind),
            ..ScriptSpec::default()
        },
    );
    let strokes = script.resolve(&mesh, "generated script")?;
    steps.finish();
    let settings = PipelineSettings {
        remeshing,
        cull,
        ..PipelineSettings::default()
    };
    // The CPU's starting mesh again for the GPU run (only then: it would double the memory).
    let start = (chosen == Backend::Both).then(|| mesh.clone());
    let mut first = match chosen {
        Backend::Both => backend::cpu(settings),
        single => backend::choose(single, settings)?,
    };
    let result = sculpt_with_progress(kind.name(), &mut mesh, &strokes, &mut first.pipeline, feed)?;
    report_fallback(&first.pipeline);
    let gpu = if let Some(mut on_gpu) = start {
        let mut second = backend::gpu(settings)?;
        let name = format!("{} (gpu)", kind.name());
        let gpu_result =
            sculpt_with_progress(&name, &mut on_gpu, &strokes, &mut second.pipeline, feed)?;
        report_fallback(&second.pipeline);
        let compared = parity((&result, &mesh), (&gpu_result, &on_gpu));
        Some((gpu_result, compared))
    } else {
        None
    };
    Ok(SceneRun { result, gpu })
}

/// A GPU that failed mid-run finished on the CPU: say so, the figures mix both.
fn report_fallback(pipeline: &slayer::pipeline::Pipeline) {
    if let Some(why) = pipeline.kernel_failure() {
        eprintln!("warning: the GPU failed ({why}); the run finished on the CPU");
    }
}

/// Runs `strokes` through `pipeline` with a progress bar, measuring as the bench does, fed as
/// `feed` says.
pub fn sculpt_with_progress(
    name: &str,
    mesh: &mut slayer::mesh::Mesh,
    strokes: &[slayer::brush::Stroke],
    pipeline: &mut slayer::pipeline::Pipeline,
    feed: Feed,
) -> anyhow::Result<SceneResult> {
    let bar = Bar::new(name, strokes.len() as u64);
    let result = run_strokes(name, mesh, strokes, pipeline, |_| bar.inc(), (true, feed))?;
    bar.finish();
    Ok(result)
}

pub fn run(options: &Options) -> anyhow::Result<ExitCode> {
    crate::strokes::check_stroke_count("--strokes", options.strokes)?;
    // Open the backend once up front: a missing GPU is an error before any work, and `auto`
    // says what it chose once; the scenes then use that choice without asking again.
    let (pipeline_name, adapter, resolved) = match options.backend {
        Backend::Both => {
            let gpu = backend::gpu(PipelineSettings::default())?;
            ("both".to_string(), gpu.adapter, Backend::Both)
        }
        other => {
            let probe = backend::choose(other, PipelineSettings::default())?;
            (probe.pipeline.name(), probe.adapter, probe.backend)
        }
    };
    let mut runs = Vec::new();
    for &kind in &options.scenes {
        let triangles = options.triangles.unwrap_or(kind.default_triangles());
        runs.push(bench_scene(
            kind,
            triangles,
            options.strokes,
            options.seed,
            (options.remeshing, resolved, options.feed(), options.cull),
        )?);
    }
    let scenes: Vec<SceneResult> = runs.iter().map(|r| r.result.clone()).collect();
    let gpu_scenes: Vec<SceneResult> = runs
        .iter()
        .filter_map(|r| r.gpu.as_ref().map(|(g, _)| g.clone()))
        .collect();
    let parities: Vec<(String, Parity)> = runs
        .iter()
        .filter_map(|r| {
            r.gpu
                .as_ref()
                .map(|(_, p)| (r.result.name.clone(), p.clone()))
        })
        .collect();
    if !scenes.is_empty() {
        println!("{}", paper_table(&scenes));
        print!("{}", topology_lines(&scenes));
        print!("{}", gpu_memory_lines(&scenes));
    }
    if !gpu_scenes.is_empty() {
        println!("the same strokes on the GPU path ({adapter}):");
        println!("{}", paper_table(&gpu_scenes));
        print!("{}", gpu_memory_lines(&gpu_scenes));
        print_parities(&parities);
    }
    let scaling = if options.scaling {
        let backend = if resolved == Backend::Both {
            Backend::Cpu
        } else {
            resolved
        };
        scaling_rows(options, backend)?
    } else {
        Vec::new()
    };
    let clean = scenes
        .iter()
        .chain(&gpu_scenes)
        .all(|s| s.valid && s.intersections == 0);
    if let Some(path) = &options.json {
        let json = serde_json::json!({
            "backend": pipeline_name,
            "adapter": adapter,
            "threads": rayon::current_num_threads(),
            "revision": slayer::bench::git_revision(),
            "scenes": scenes,
            "scaling": if options.scaling { Some(&scaling) } else { None },
            "gpu_scenes": if gpu_scenes.is_empty() { None } else { Some(&gpu_scenes) },
            // docs/bench.md's `parity` is one object: the first scene's; every scene's is in
            // `parity_by_scene`.
            "parity": parities.first().map(|(_, p)| p),
            "parity_by_scene": if parities.is_empty() { None } else { Some(&parities) },
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

/// One line per scene comparing the GPU path with the CPU's.
fn print_parities(parities: &[(String, Parity)]) {
    for (name, p) in parities {
        println!(
            "parity {name}: max position deviation {}, collisions cpu {} gpu {}; gpu/cpu time: {}",
            p.max_position_deviation_edges.map_or(
                "n/a (remeshing made the topologies differ)".to_string(),
                |d| format!("{d:.2e} L")
            ),
            p.collision_count_cpu,
            p.collision_count_gpu,
            p.gpu_over_cpu
                .iter()
                .map(|(k, v)| format!("{k} {v:.2}x"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
}

/// `--scaling`: the same strokes (at most 8) on plaster at each of the sizes, printed as a
/// table.
fn scaling_rows(options: &Options, backend: Backend) -> anyhow::Result<Vec<ScalingRow>> {
    let mut scaling = Vec::new();
    for &faces in &options.scaling_sizes {
        let r = bench_scene(
            SceneKind::Plaster,
            faces,
            options.strokes.min(8),
            options.seed,
            (options.remeshing, backend, options.feed(), options.cull),
        )?
        .result;
        scaling.push(ScalingRow {
            faces: r.faces,
            ms_per_sample: r.ms_per_sample,
            ms_per_remesh: r.ms_per_remesh,
            samples: r.samples,
            steps: r.steps,
            moves: r.moves,
            peak_heap_bytes: r.peak_heap_bytes,
            gpu_memory: r.gpu_memory,
        });
    }
    println!("scaling: the same strokes (radius 12 L) on plaster of growing size");
    println!("{}", scaling_table(&scaling));
    Ok(scaling)
}

fn write_svg(path: &Path, rows: &[ScalingRow]) -> anyhow::Result<()> {
    let svg = scaling_svg(rows, "slayer: ms per stroke sample against mesh size (CPU)");
    slayer::io::write_atomically(path, svg.as_bytes()).context("writing the scaling plot")?;
    println!("scaling plot: {}", path.display());
    Ok(())
}
