//! The GPU's proximity passes culled as the CPU's searches are (lavapipe in CI, never skipped):
//! a step whose region is one layer and a clear sheet where its moves end runs no passes, and
//! steps recorded ahead without them on that expectation are checked before they are taken.
//! On a flat sheet and a narrow groove whose walls meet, with runs
//! ahead on and off, the GPU must end where the CPU pipeline does, with the same clamps, and its
//! copy of the mesh must be the mesh row for row.

mod common;

use common::reshaped;
use glam::Vec3;
use slayer::bench::{BrushMix, ScriptSpec, generate_script};
use slayer::brush::{BrushKind, Stroke};
use slayer::collide::find_intersections;
use slayer::gpu::{AdapterChoice, GpuContext, GpuKernels};
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings, Remeshing, Uploads};
use slayer::scene::{SceneKind, SceneSpec, generate};

fn plane(triangles: usize) -> Mesh {
    generate(&SceneSpec {
        kind: SceneKind::Plane,
        triangles,
        seed: 3,
    })
    .unwrap()
}

/// A draw on layer 0 of `radius` at full strength through `positions`, pushing along
/// `normal`.
fn draw(radius: f32, positions: impl Iterator<Item = Vec3>, normal: Vec3) -> Stroke {
    let samples: Vec<Vec3> = positions.collect();
    let mut stroke = common::one_brush_stroke(BrushKind::Draw, radius, &samples);
    for sample in &mut stroke.samples {
        sample.normal = Some(normal);
    }
    stroke
}

/// What one run of the strokes did.
struct Run {
    mesh: Mesh,
    clamped: usize,
    reverted: usize,
    steps: usize,
    culled_steps: usize,
    uploads: Option<Uploads>,
}

/// Runs `strokes` on `mesh` through `pipeline`.
fn run(mut pipeline: Pipeline, mesh: &Mesh, strokes: &[Stroke]) -> Run {
    let mut mesh = mesh.clone();
    let (mut clamped, mut reverted, mut steps, mut culled_steps) = (0, 0, 0, 0);
    for stroke in strokes {
        let report = pipeline.apply_stroke(&mut mesh, stroke).unwrap();
        clamped += report.clamped;
        reverted += report.reverted;
        steps += report.steps;
        culled_steps += report.culled_steps;
    }
    assert_eq!(pipeline.kernel_failure(), None);
    let uploads = pipeline.uploads();
    if uploads.is_some() {
        pipeline.check_kernel_copy(&mesh).unwrap();
    }
    mesh.validate().unwrap();
    assert_eq!(find_intersections(&mesh).total(), 0);
    Run {
        mesh,
        clamped,
        reverted,
        steps,
        culled_steps,
        uploads,
    }
}

/// A pipeline with the proximity passes on the GPU (a software adapter leaves them on the CPU
/// by default), runs ahead as given, and whether its adapter is a software one.
fn on_gpu(settings: PipelineSettings, runs_ahead: bool) -> (Pipeline, bool) {
    let gpu = GpuContext::new(AdapterChoice {
        allow_software: true,
    })
    .unwrap_or_else(|e| panic!("GPU tests need an adapter (run tools/test.sh): {e}"));
    let mut kernels = GpuKernels::new(gpu);
    kernels.set_proximity_on_gpu(true);
    kernels.set_run_ahead(runs_ahead);
    let software = kernels.adapter().software;
    (
        Pipeline::with_kernels(settings, Box::new(kernels)),
        software,
    )
}

/// What the culled runs on the GPU counted, runs ahead off and on, beside the CPU's run.
struct Culled {
    apart: Uploads,
    ahead: Uploads,
    on_cpu: Run,
}

/// Runs `strokes` on the CPU, then on the GPU culled with runs ahead off and on, and unculled;
/// each GPU run must end as the CPU's (within 1e-4·L, the same on lavapipe), with its clamps
/// and undos.
fn assert_gpu_culls_as_the_cpu(name: &str, mesh: &Mesh, strokes: &[Stroke]) -> Culled {
    let edge = mesh.mean_edge_length();
    let settings = |cull| PipelineSettings {
        remeshing: Remeshing::Off,
        cull,
        ..PipelineSettings::default()
    };
    let on_cpu = run(Pipeline::new(settings(true)), mesh, strokes);
    let mut culled = Vec::new();
    for (cull, runs_ahead) in [(true, false), (true, true), (false, false)] {
        let label = format!("{name}, culled {cull}, runs ahead {runs_ahead}");
        let (pipeline, software) = on_gpu(settings(cull), runs_ahead);
        let on_gpu = run(pipeline, mesh, strokes);
        let uploads = on_gpu.uploads.expect("GPU kernels keep a copy");
        let deviation = (on_cpu.mesh.positions().iter())
            .zip(on_gpu.mesh.positions())
            .map(|(p, q)| p.distance(*q))
            .fold(0.0f32, f32::max);
        eprintln!(
            "{label}: {} steps, {} culled on the CPU; GPU passes skipped {}, needed after all {}, \
             clamps {} (CPU {}), deviation {:.2e} L",
            on_gpu.steps,
            on_cpu.culled_steps,
            uploads.skipped_passes,
            uploads.passes_needed,
            on_gpu.clamped,
            on_cpu.clamped,
            deviation / edge
        );
        assert!(deviation <= 1e-4 * edge, "{label}: {deviation} > 1e-4 L");
        if software {
            assert_eq!(
                (on_gpu.clamped, on_gpu.reverted),
                (on_cpu.clamped, on_cpu.reverted),
                "{label}"
            );
        }
        if cull {
            culled.push(uploads);
        } else {
            assert_eq!(
                (uploads.skipped_passes, uploads.passes_needed),
                (0, 0),
                "{label}"
            );
        }
    }
    Culled {
        apart: culled[0],
        ahead: culled[1],
        on_cpu,
    }
}

#[test]
fn the_gpu_runs_no_passes_for_a_plain_draw_on_a_flat_sheet() {
    let mesh = plane(6_000);
    let spec = ScriptSpec {
        strokes: 3,
        seed: 5,
        samples: 10,
        mix: BrushMix::StraightDraw,
        ..ScriptSpec::default()
    };
    let strokes = generate_script(&mesh, &spec)
        .resolve(&mesh, "script")
        .unwrap();
    let Culled {
        apart,
        ahead,
        on_cpu,
    } = assert_gpu_culls_as_the_cpu("flat sheet", &mesh, &strokes);
    // The GPU skips its passes wherever the CPU culled the whole step.
    // The GPU skips its passes where the CPU culled the whole step, but for steps of a run
    // recorded with its passes before a test found the sheet clear again (those of a step
    // whose region reached the sheet's rim, and after).
    let culled = on_cpu.culled_steps;
    assert!(
        culled * 2 > on_cpu.steps,
        "{culled} of {} steps",
        on_cpu.steps
    );
    for (uploads, share) in [(apart, 0.75), (ahead, 0.33)] {
        let skipped = uploads.skipped_passes;
        assert!(
            skipped as f32 >= share * culled as f32 && skipped <= culled,
            "{uploads:?}: {culled} culled on the CPU"
        );
    }
    // Runs ahead still take their samples in one submission each.
    assert!(
        ahead.samples_ahead > ahead.batches && ahead.batches > 0,
        "{ahead:?}"
    );
}

#[test]
fn where_a_sheet_meets_itself_the_gpu_runs_its_passes() {
    // A V-shaped groove with walls at 79° in a flat sheet: a sheet, but too steep to be clear.
    // Draws pushing its left wall sideways into the right one collide; the mesh is one layer,
    // so the GPU expects a clear sheet at first and records its first steps without passes,
    // which the host's test then finds needed.
    let mesh = reshaped(plane(4_000), |u, v| {
        let across = ((u - 0.5) / 0.04).abs();
        Vec3::new(u, v, -0.2 * (1.0 - across).max(0.0))
    });
    let into_the_far_wall = |depth: f32| {
        let to = |k: usize| Vec3::new(0.485, 0.4 + 0.2 * ((k % 8) as f32 / 7.0), depth);
        draw(0.03, (0..16).map(to), Vec3::X)
    };
    let strokes: Vec<Stroke> = [-0.13, -0.12].map(into_the_far_wall).into();
    let Culled {
        apart,
        ahead,
        on_cpu,
    } = assert_gpu_culls_as_the_cpu("narrow groove", &mesh, &strokes);
    assert!(on_cpu.clamped > 0, "the groove's walls must meet");
    for uploads in [apart, ahead] {
        assert!(uploads.passes_needed > 0, "{uploads:?}");
    }
}
