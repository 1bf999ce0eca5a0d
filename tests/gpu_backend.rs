//! The pipeline with the GPU's selection, deformation and proximity passes (lavapipe in CI, never
//! skipped) against the CPU pipeline on the same strokes: positions, collision counts,
//! soundness, and the fallback to the CPU when the GPU is lost mid-stroke.

mod common;

use slayer::bench::{ScriptSpec, generate_script};
use slayer::collide::find_intersections;
use slayer::gpu::{AdapterChoice, GpuContext, GpuKernels, PackedTopology};
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings, Remeshing};
use slayer::scene::{SceneKind, SceneSpec, generate};

fn gpu() -> GpuContext {
    GpuContext::new(AdapterChoice {
        allow_software: true,
    })
    .unwrap_or_else(|e| panic!("GPU tests need an adapter (run tools/test.sh): {e}"))
}

/// GPU kernels with every step kernel on the GPU, proximity passes included (a software
/// adapter leaves those on the CPU by default), one submission per step: runs ahead are on by
/// default on a hardware adapter only, so they are pinned off for every adapter to run the
/// same path (the runs-ahead tests turn them on).
fn all_on_gpu() -> GpuKernels {
    let mut kernels = GpuKernels::new(gpu());
    kernels.set_proximity_on_gpu(true);
    kernels.set_run_ahead(false);
    kernels
}

/// Whether counts of discrete outcomes (clamps, reverted moves) agree between the backends:
/// exactly on lavapipe; within 0.5 % and one on a hardware GPU, where a move that ends at a
/// threshold may go either way ([`rounds_as_the_cpu`]).
fn counts_agree(cpu: usize, gpu: usize) -> bool {
    cpu == gpu || (!rounds_as_the_cpu() && cpu.abs_diff(gpu) <= 1 + cpu / 200)
}

/// How large a test's strokes are. On lavapipe every proximity pass costs in proportion to the
/// vertices a step moves (about 9 s a sample for the bench's strokes, radius 12·L, all on the
/// GPU), so each test takes the fewest and smallest strokes that still run what it checks
/// (and asserts that they do: collisions, runs ahead, extra steps, remeshing).
#[derive(Clone, Copy)]
struct Size {
    strokes: usize,
    samples: usize,
    radius_edges: f32,
}

/// Two short strokes of a brush half the bench's: enough to collide on every path.
const SHORT: Size = Size {
    strokes: 2,
    samples: 10,
    radius_edges: 6.0,
};

/// The plaster scene, remeshed once to its mean edge as sculpting keeps it: the generated
/// scene has a few edges 3.5 times the mean around its holes, and the broad phase's reach
/// (and the GPU's work per moving vertex, cubed) follows the longest edge.
fn plaster_and_strokes(size: Size) -> (Mesh, Vec<slayer::brush::Stroke>) {
    let mut mesh = generate(&SceneSpec {
        kind: SceneKind::Plaster,
        triangles: 2_000,
        seed: 9,
    })
    .unwrap();
    let edge = mesh.mean_edge_length();
    slayer::remesh::remesh_all(&mut mesh, &slayer::remesh::RemeshSettings::new(edge)).unwrap();
    let script = generate_script(
        &mesh,
        &ScriptSpec {
            strokes: size.strokes,
            seed: 9,
            samples: size.samples,
            radius_edges: size.radius_edges,
            ..ScriptSpec::default()
        },
    );
    let strokes = script.resolve(&mesh, "script").unwrap();
    (mesh, strokes)
}

/// Runs `strokes` and returns the collision count.
fn run(pipeline: &mut Pipeline, mesh: &mut Mesh, strokes: &[slayer::brush::Stroke]) -> usize {
    strokes
        .iter()
        .map(|s| pipeline.apply_stroke(mesh, s).unwrap().clamped)
        .sum()
}

/// Whether the adapter rounds as the CPU does: lavapipe does (its kernels are compiled for the
/// CPU without fusing multiply-adds); a hardware GPU rounds within WGSL's bounds instead, so a
/// move that ends exactly at a remeshing or collision threshold may go the other way there.
fn rounds_as_the_cpu() -> bool {
    static SOFTWARE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *SOFTWARE.get_or_init(|| gpu().adapter.software)
}

/// Asserts that the GPU backend's mesh is the CPU pipeline's: the same vertices within 1e-4·`edge`.
/// On a hardware GPU a threshold decided the other way can make remeshing choose differently
/// from there on (another split, the vertices numbered otherwise), so there, failing that, the
/// same surface: vertex counts within 1 %, each surface within 0.1·`edge` of the other.
fn assert_matches_cpu(label: &str, on_cpu: &Mesh, on_gpu: &Mesh, edge: f32) {
    let same_vertices = on_cpu.vertex_count() == on_gpu.vertex_count();
    let deviation = if same_vertices {
        largest_deviation(on_cpu, on_gpu)
    } else {
        f32::INFINITY
    };
    eprintln!("{label}: largest deviation {:.2e} L", deviation / edge);
    if deviation <= 1e-4 * edge {
        return;
    }
    assert!(
        !rounds_as_the_cpu(),
        "{label}: vertices {} vs {}, deviation {deviation} > 1e-4 L",
        on_cpu.vertex_count(),
        on_gpu.vertex_count()
    );
    let (c, g) = (on_cpu.live_vertex_count(), on_gpu.live_vertex_count());
    assert!(
        c.abs_diff(g) <= c / 100,
        "{label}: {c} live vertices on the CPU, {g} on the GPU"
    );
    let apart = |a: &Mesh, b: &Mesh| slayer::remesh::Surface::of(a).distance_of(b, edge).max;
    let apart = apart(on_cpu, on_gpu).max(apart(on_gpu, on_cpu));
    eprintln!("{label}: remeshing chose otherwise; the surfaces lie {apart:.3} L apart");
    assert!(apart <= 0.1, "{label}: the surfaces lie {apart} L apart");
}

/// Asserts that two selections in vertex order hold the same vertices, but for those within
/// 1e-5 of the rim (`reach`: a vertex's distance from the centre over the radius), with weights
/// within 1e-5: a hardware GPU's rounding (see [`rounds_as_the_cpu`]).
fn assert_selections_agree(
    label: &str,
    gpu: &[(u32, f32)],
    cpu: &[(u32, f32)],
    reach: impl Fn(u32) -> f32,
) {
    let on_rim = |v: u32| (reach(v) - 1.0).abs() <= 1e-5;
    let weights: std::collections::HashMap<u32, f32> = cpu.iter().copied().collect();
    for &(v, w) in gpu {
        match weights.get(&v) {
            Some(&c) => assert!(
                (w - c).abs() <= 1e-5,
                "{label}: vertex {v} weighs {w} vs {c}"
            ),
            None => assert!(
                on_rim(v),
                "{label}: vertex {v} selected at {} of the radius",
                reach(v)
            ),
        }
    }
    let selected: std::collections::HashSet<u32> = gpu.iter().map(|&(v, _)| v).collect();
    for &(v, _) in cpu {
        assert!(
            selected.contains(&v) || on_rim(v),
            "{label}: vertex {v} left out at {} of the radius",
            reach(v)
        );
    }
}

/// The largest distance between the same vertex of two meshes.
fn largest_deviation(a: &Mesh, b: &Mesh) -> f32 {
    a.positions()
        .iter()
        .zip(b.positions())
        .map(|(p, q)| p.distance(*q))
        .fold(0.0f32, f32::max)
}

#[test]
fn gpu_selection_and_deformation_match_the_cpu_pipeline() {
    let (start, strokes) = plaster_and_strokes(SHORT);
    let edge = start.mean_edge_length();
    // Without remeshing the two meshes keep the same vertices and can be compared one by one.
    let settings = PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    };
    let (mut on_cpu, mut on_gpu) = (start.clone(), start.clone());
    let cpu_collisions = run(&mut Pipeline::new(settings), &mut on_cpu, &strokes);
    let mut gpu_pipeline = Pipeline::with_kernels(settings, Box::new(all_on_gpu()));
    let gpu_collisions = run(&mut gpu_pipeline, &mut on_gpu, &strokes);
    assert_eq!(gpu_pipeline.kernel_failure(), None);
    let deviation = largest_deviation(&on_cpu, &on_gpu);
    let uploads = gpu_pipeline.uploads().expect("GPU kernels keep a copy");
    eprintln!(
        "max deviation {deviation:e} ({:.2e} L), collisions cpu {cpu_collisions} gpu {gpu_collisions}; {uploads:?}",
        deviation / edge
    );
    assert!(deviation <= 1e-4 * edge, "{deviation} > 1e-4 L");
    // Most steps ran their proximity passes in the submission that selected and deformed.
    assert!(uploads.clamped_ahead > uploads.dropped_ahead, "{uploads:?}");
    assert!(cpu_collisions > 0, "the strokes collide");
    let spread = (cpu_collisions as f64 - gpu_collisions as f64).abs() / cpu_collisions as f64;
    assert!(spread <= 0.005, "{cpu_collisions} vs {gpu_collisions}");
    for mesh in [&on_cpu, &on_gpu] {
        mesh.validate().unwrap();
        assert_eq!(find_intersections(mesh).total(), 0);
    }
}

/// A stroke's samples run ahead several to a submission (selection, frame, deformation, moving
/// entries, proximity passes, filter and the normals each sample turned, each sample reading
/// what the one before left on the GPU): the pipeline takes them as it would have asked for
/// them, with the CPU pipeline's result, fewer read-backs than samples, and the GPU's copy the
/// mesh row for row after the stroke.
#[test]
fn samples_run_ahead_in_one_submission_match_the_cpu_pipeline() {
    // The bench's stroke, whose samples each move less than a step (smaller brushes, with
    // the same path, press harder per sample and take several).
    let (start, strokes) = plaster_and_strokes(Size {
        strokes: 1,
        samples: 32,
        radius_edges: 12.0,
    });
    let report = check_run_ahead(&start, &strokes, PipelineSettings::default().max_step);
    assert_eq!(report.steps, report.samples, "one step a sample");
    assert!(report.uploads.read_backs < report.samples, "{report:?}");
}

/// An inflating stroke pressed lightly, then harder, then lightly, with steps of half an edge:
/// its middle samples move farther than a step, by two steps or three. A run records the two
/// steps of a sample that may take two right after its start, which defers its move to them
/// when it takes two; the gate stops a run at the start of a sample of three, which the
/// pipeline takes from what the run read, and its steps and the samples after it then run
/// ahead in one submission. Each step deforms on the normals from before the sample (inflate
/// moves along them), the normals recomputed after its last. The result is the CPU pipeline's,
/// in fewer read-backs than steps. (The exact backstop undoes moves runs made, which drops what
/// they recorded after them; over the second stroke where the run's normals around such a move
/// are read again before the pipeline refreshes them: they must go back with the move.)
#[test]
fn samples_of_several_steps_run_their_steps_ahead_and_match_the_cpu_pipeline() {
    let (start, mut strokes) = plaster_and_strokes(Size {
        samples: 12,
        radius_edges: 12.0,
        ..SHORT
    });
    for stroke in &mut strokes {
        stroke.brush.kind = slayer::brush::BrushKind::Inflate;
        stroke.brush.strength = 1.0;
        let n = stroke.samples.len();
        for (i, sample) in stroke.samples.iter_mut().enumerate() {
            // Moves of 0.36, 0.84 and 1.2 edges: one, two and three steps of half an edge.
            sample.pressure = match (n / 3..2 * n / 3).contains(&i) {
                true if i == n / 2 => 1.0,
                true => 0.7,
                false => 0.3,
            };
        }
    }
    let report = check_run_ahead(&start, &strokes, 0.55);
    assert!(report.steps > report.samples, "{report:?}");
    // Samples of two steps went on in their run...
    assert!(report.uploads.split_ahead > 0, "{report:?}");
    // ...those of three stopped it, and are counted as such.
    assert!(report.uploads.gate_stops.several_steps > 0, "{report:?}");
    assert!(report.uploads.steps_ahead > 0, "{report:?}");
}

struct RunAheadReport {
    samples: usize,
    steps: usize,
    uploads: slayer::pipeline::Uploads,
}

impl std::fmt::Debug for RunAheadReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} samples in {} steps; {:?}",
            self.samples, self.steps, self.uploads
        )
    }
}

/// Runs `strokes` on the CPU and with everything on the GPU, runs ahead on (steps of at most
/// `max_step` edges), and checks that
/// the GPU ran samples ahead, read back fewer times than it took steps (one submission per
/// step reads back at least once a step), and matched the CPU pipeline's result, its copy the
/// mesh row for row after the strokes.
fn check_run_ahead(
    start: &Mesh,
    strokes: &[slayer::brush::Stroke],
    max_step: f32,
) -> RunAheadReport {
    let edge = start.mean_edge_length();
    let settings = PipelineSettings {
        remeshing: Remeshing::Off,
        max_step,
        ..PipelineSettings::default()
    };
    let (mut on_cpu, mut on_gpu) = (start.clone(), start.clone());
    let cpu_collisions = run(&mut Pipeline::new(settings), &mut on_cpu, strokes);
    let mut kernels = all_on_gpu();
    kernels.set_run_ahead(true);
    // What the GPU files between samples is read back and checked before the host refiles.
    kernels.set_check_filing(true);
    let mut pipeline = Pipeline::with_kernels(settings, Box::new(kernels));
    let mut gpu_collisions = 0;
    let (mut samples, mut steps) = (0, 0);
    for stroke in strokes {
        let report = pipeline.apply_stroke(&mut on_gpu, stroke).unwrap();
        gpu_collisions += report.clamped;
        samples += report.samples;
        steps += report.steps;
    }
    assert_eq!(pipeline.kernel_failure(), None);
    // Before the check, which reads the whole copy back.
    let uploads = pipeline.uploads().expect("GPU kernels keep a copy");
    pipeline.check_kernel_copy(&on_gpu).unwrap();
    let deviation = largest_deviation(&on_cpu, &on_gpu);
    let report = RunAheadReport {
        samples,
        steps,
        uploads,
    };
    eprintln!(
        "max deviation {deviation:e} ({:.2e} L), collisions cpu {cpu_collisions} gpu \
         {gpu_collisions}; {report:?}",
        deviation / edge
    );
    assert!(
        uploads.batches > 0 && uploads.samples_ahead > uploads.batches,
        "{report:?}"
    );
    assert!(uploads.read_backs < steps, "{report:?}");
    assert!(deviation <= 1e-4 * edge, "{deviation} > 1e-4 L");
    assert!(cpu_collisions > 0, "the stroke collides");
    let spread = (cpu_collisions as f64 - gpu_collisions as f64).abs() / cpu_collisions as f64;
    assert!(spread <= 0.005, "{cpu_collisions} vs {gpu_collisions}");
    on_gpu.validate().unwrap();
    assert_eq!(find_intersections(&on_gpu).total(), 0);
    report
}

/// With remeshing after every stroke the GPU's copy is patched where remeshing changed the mesh
/// (rows of changed vertices, their neighbours and faces), never sent whole again, and after
/// every stroke it is the mesh row for row; the vertices remeshing changed are filed in the
/// hash table's overlay. The strokes give what the CPU pipeline gives, with the proximity
/// passes on the GPU (which rebuild the table as vertices drift half a cell) and without (where
/// selection rebuilds it only after a quarter of the brush radius of drift).
#[test]
fn gpu_kernels_with_remeshing_patch_their_copy_and_keep_the_mesh_sound() {
    let (start, strokes) = plaster_and_strokes(SHORT);
    let settings = PipelineSettings::default();
    let mut on_cpu = start.clone();
    let mut cpu_pipeline = Pipeline::new(settings);
    let (mut cpu_collisions, mut cpu_reverted) = (0, 0);
    for stroke in &strokes {
        let report = cpu_pipeline.apply_stroke(&mut on_cpu, stroke).unwrap();
        cpu_collisions += report.clamped;
        cpu_reverted += report.reverted;
    }
    for proximity_on_gpu in [true, false] {
        let mut kernels = all_on_gpu();
        kernels.set_proximity_on_gpu(proximity_on_gpu);
        let mut mesh = start.clone();
        let mut pipeline = Pipeline::with_kernels(settings, Box::new(kernels));
        let (mut gpu_collisions, mut gpu_reverted) = (0, 0);
        for stroke in &strokes {
            let report = pipeline.apply_stroke(&mut mesh, stroke).unwrap();
            assert!(
                report.remesh.splits + report.remesh.collapses > 0,
                "remeshing edits"
            );
            gpu_collisions += report.clamped;
            gpu_reverted += report.reverted;
            pipeline.check_kernel_copy(&mesh).unwrap();
        }
        assert_eq!(pipeline.kernel_failure(), None);
        let uploads = pipeline.uploads().expect("GPU kernels keep a copy");
        let filter = pipeline.backstop_filter();
        eprintln!(
            "proximity on the GPU: {proximity_on_gpu}, {uploads:?}, {filter:?}, \
             reverted {gpu_reverted} (cpu {cpu_reverted})"
        );
        // With the passes on the GPU, so is the backstop's filter: every step's first round.
        if proximity_on_gpu {
            let filter = filter.expect("the GPU filters the backstop");
            assert!(filter.filtered > 0 && filter.overflowed == 0, "{filter:?}");
        } else {
            assert_eq!(filter, None);
        }
        assert!(
            counts_agree(cpu_reverted, gpu_reverted),
            "reverted {cpu_reverted} on the CPU, {gpu_reverted} on the GPU"
        );
        // Sent whole once; patched after every stroke (and where a grab remeshed mid-stroke).
        assert_eq!(uploads.whole, 1, "{uploads:?}");
        assert!(uploads.patched >= strokes.len(), "{uploads:?}");
        assert!(uploads.overlay_filings > 0, "the overlay is used");
        assert!(
            mesh.vertex_count() > start.vertex_count(),
            "remeshing added vertices"
        );
        let label = format!("proximity on the GPU: {proximity_on_gpu}");
        assert_matches_cpu(&label, &on_cpu, &mesh, start.mean_edge_length());
        assert!(
            counts_agree(cpu_collisions, gpu_collisions),
            "{cpu_collisions} vs {gpu_collisions}"
        );
        mesh.validate().unwrap();
        assert_eq!(find_intersections(&mesh).total(), 0);
    }
}

/// Two edges crossing where no vertex comes within the collision distance of the other face,
/// with every pass on the GPU (its backstop filter included): the proximity passes see
/// nothing, and the exact backstop undoes the crossing as on the CPU.
#[test]
fn the_backstop_undoes_a_crossing_the_gpu_passes_cannot_see() {
    let (start, stroke) = common::crossing_edges(1.0);
    let settings = PipelineSettings {
        collision_distance: 0.25,
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    };
    let mut on_cpu = start.clone();
    let cpu = Pipeline::new(settings)
        .apply_stroke(&mut on_cpu, &stroke)
        .unwrap();
    let mut mesh = start.clone();
    let mut pipeline = Pipeline::with_kernels(settings, Box::new(all_on_gpu()));
    let gpu = pipeline.apply_stroke(&mut mesh, &stroke).unwrap();
    assert_eq!(pipeline.kernel_failure(), None);
    assert_eq!(gpu.clamped, 0, "the passes saw it: {gpu:?}");
    assert!(gpu.reverted > 0, "nothing was undone: {gpu:?}");
    assert_eq!(gpu.reverted, cpu.reverted);
    assert!(largest_deviation(&on_cpu, &mesh) <= 1e-4 * start.mean_edge_length());
    assert_eq!(find_intersections(&mesh).total(), 0);
}

/// A GPU lost in the middle of a stroke: the stroke finishes on the CPU, the failure is
/// reported, and the result is what the CPU alone makes.
#[test]
fn a_gpu_lost_mid_stroke_finishes_on_the_cpu() {
    let (start, strokes) = plaster_and_strokes(SHORT);
    let settings = PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    };
    let mut on_cpu = start.clone();
    run(&mut Pipeline::new(settings), &mut on_cpu, &strokes);
    let mut kernels = all_on_gpu();
    kernels.fail_after(7);
    let mut pipeline = Pipeline::with_kernels(settings, Box::new(kernels));
    let mut mesh = start.clone();
    run(&mut pipeline, &mut mesh, &strokes);
    let failure = pipeline
        .kernel_failure()
        .expect("the simulated loss is reported");
    assert!(failure.contains("device lost"), "{failure}");
    mesh.validate().unwrap();
    assert_eq!(find_intersections(&mesh).total(), 0);
    let deviation = largest_deviation(&on_cpu, &mesh);
    assert!(deviation <= 1e-4 * start.mean_edge_length(), "{deviation}");
}

/// A mesh over our own GPU memory budget is not uploaded: the kernels say why, and the strokes
/// run on the CPU with the CPU's result.
#[test]
fn a_mesh_over_the_gpu_budget_runs_on_the_cpu() {
    let (start, strokes) = plaster_and_strokes(SHORT);
    let settings = PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    };
    let mut on_cpu = start.clone();
    run(&mut Pipeline::new(settings), &mut on_cpu, &strokes);
    let mut gpu = gpu();
    let needed = slayer::gpu::resident_bytes(&start);
    assert!(needed > 100_000, "{needed} bytes");
    gpu.budget_bytes = needed / 2;
    let mut kernels = GpuKernels::new(gpu);
    kernels.set_proximity_on_gpu(true);
    let mut pipeline = Pipeline::with_kernels(settings, Box::new(kernels));
    let mut mesh = start.clone();
    run(&mut pipeline, &mut mesh, &strokes);
    let failure = pipeline.kernel_failure().expect("the budget is reported");
    assert!(failure.contains("budget"), "{failure}");
    assert_eq!(mesh.positions(), on_cpu.positions());
}

/// An adapter whose storage bindings are a few KiB: the packed topology and the smoothing
/// neighbours are bound as several pages, and the strokes give the CPU's result.
#[test]
fn arrays_past_the_binding_limit_are_split_into_pages() {
    let (start, strokes) = plaster_and_strokes(SHORT);
    let settings = PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    };
    // As the backend keeps them: with room for what remeshing adds.
    let capacity = slayer::gpu::vertex_capacity(start.vertex_count());
    let faces = slayer::gpu::face_capacity(start.face_count());
    let topology = 4 * PackedTopology::with_room(&start, faces, capacity)
        .words
        .len() as u64;
    let neighbours = 4 * slayer::gpu::smoothing_neighbours(&start, capacity)
        .words
        .len() as u64;
    // Large enough for every array bound whole (12 bytes a vertex at most, and the hash
    // table's offsets) and for the paged ones in four pages.
    let whole = (12 * capacity as u64)
        .max(4 * (slayer::gpu::table_size_for(start.vertex_count()) as u64 + 1));
    let limit = whole
        .max(topology.div_ceil(slayer::gpu::PAGE_COUNT))
        .next_power_of_two();
    let gpu = GpuContext::with_limits(
        AdapterChoice {
            allow_software: true,
        },
        |limits| limits.max_storage_buffer_binding_size = limit,
    )
    .unwrap();
    let (topology_pages, neighbour_pages) = (
        gpu.pages_for(topology as usize / 4),
        gpu.pages_for(neighbours as usize / 4),
    );
    eprintln!(
        "binding limit {limit} bytes: topology {topology} bytes in {topology_pages} pages, \
         neighbours {neighbours} bytes in {neighbour_pages}"
    );
    assert!(
        topology_pages >= 2 && neighbour_pages >= 1,
        "paging is exercised"
    );

    let mut on_cpu = start.clone();
    let cpu_collisions = run(&mut Pipeline::new(settings), &mut on_cpu, &strokes);
    let mut kernels = GpuKernels::new(gpu);
    kernels.set_proximity_on_gpu(true);
    let mut pipeline = Pipeline::with_kernels(settings, Box::new(kernels));
    let mut mesh = start.clone();
    let gpu_collisions = run(&mut pipeline, &mut mesh, &strokes);
    assert_eq!(pipeline.kernel_failure(), None);
    assert_matches_cpu("paged", &on_cpu, &mesh, start.mean_edge_length());
    assert!(
        counts_agree(cpu_collisions, gpu_collisions),
        "{cpu_collisions} vs {gpu_collisions}"
    );
    assert!(cpu_collisions > 0, "the strokes collide");
}

/// Remeshing files the vertices it changed (new ones among them) in the hash table's overlay
/// instead of rebuilding the table: selection right after finds them — exactly what the CPU's
/// selection finds — with the table built once.
#[test]
fn selection_after_remeshing_finds_new_vertices_through_the_overlay() {
    use slayer::brush::{Brush, BrushKind, Dab, DabFrame, Falloff};
    use slayer::collide::StrokeState;
    use slayer::grid::SpatialHash;
    use slayer::pipeline::{CpuKernels, StepKernels};

    let (mut mesh, _) = plaster_and_strokes(Size {
        strokes: 0,
        ..SHORT
    });
    let edge = mesh.mean_edge_length();
    let center = mesh.positions()[mesh.vertex_count() / 2];
    let dab = Dab {
        brush: Brush {
            kind: BrushKind::Draw,
            radius: 3.0 * edge,
            strength: 0.5,
            falloff: Falloff::Smooth,
            invert: false,
        },
        frame: DabFrame {
            center,
            normal: glam::Vec3::Z,
            plane_point: center,
            motion: glam::Vec3::ZERO,
        },
        pressure: 1.0,
        share: 1.0,
    };
    let active = vec![true; mesh.layer_count()];
    fn state_with<'a>(grid: &'a SpatialHash, active: &'a [bool], edge: f32) -> StrokeState<'a> {
        StrokeState {
            grid: Some(grid),
            active,
            parallel: false,
            collision_distance: edge,
            ring: 2,
            max_edge: 2.0 * edge,
            cull: true,
        }
    }
    let mut kernels = all_on_gpu();
    let mut grid = SpatialHash::build(&mesh, edge).unwrap();
    let before = kernels.select(&state_with(&grid, &active, edge), &mesh, &dab);
    assert!(!before.is_empty());

    // Remeshed finer under the brush: every edge there splits.
    let since = mesh.version();
    let old_count = mesh.vertex_count();
    let seeds: Vec<u32> = before.iter().map(|&(v, _)| v).collect();
    let settings = slayer::remesh::RemeshSettings::new(0.5 * edge);
    let (report, changed) = slayer::remesh::remesh_region(&mut mesh, &mut grid, &seeds, &settings);
    assert!(report.splits > 0);
    kernels.remeshed(&mesh, since, &changed);

    let state = state_with(&grid, &active, edge);
    let after = kernels.select(&state, &mesh, &dab);
    let expected = CpuKernels.select(&state, &mesh, &dab);
    let ids = |s: &[(u32, f32)]| s.iter().map(|&(v, _)| v).collect::<Vec<_>>();
    assert_eq!(ids(&after), ids(&expected));
    for (&(v, w), &(_, e)) in after.iter().zip(&expected) {
        assert!(
            (w - e).abs() <= 1e-5,
            "vertex {v}: weight {w}, {e} on the CPU"
        );
    }
    let new = after
        .iter()
        .filter(|&&(v, _)| v as usize >= old_count)
        .count();
    assert!(new > 0, "new vertices are selected");
    let uploads = kernels.uploads().expect("GPU kernels keep a copy");
    assert_eq!((uploads.table_builds, uploads.overlay_filings), (1, 1));
    assert_eq!(kernels.failure(), None);
}

#[test]
fn select_and_deform_is_one_read_back_and_matches_the_cpu_kernels() {
    // At a sample's start (the frame from the selection, with and without the sample's own
    // normal) and at a later step (the dab's frame), for a brush that does not deform, and for
    // a selection longer than the GPU guessed (its second read and separate deformation): the
    // same vertices and weights as the CPU kernels, the same frame bits (the sums are integers,
    // turned into the frame by the same function), and the same targets within rounding.
    use glam::Vec3;
    use slayer::brush::{Brush, BrushKind, Dab, DabFrame, Falloff};
    use slayer::collide::StrokeState;
    use slayer::pipeline::{CpuKernels, FrameSource, StepKernels};

    // Vertices numbered in no spatial order, so that the GPU appends its selection out of
    // vertex order and its targets must be put in the pipeline's order.
    let sheets = slayer::scene::shapes::stacked_sheets(3, 120, 100, 0.05, 0.2);
    let count = sheets.vertex_count() as u32;
    let new_id = |v: u32| (v as u64 * 7919 % count as u64) as u32;
    let mut positions = vec![Vec3::ZERO; count as usize];
    for (v, p) in sheets.positions().iter().enumerate() {
        positions[new_id(v as u32) as usize] = *p;
    }
    let faces = sheets.faces().iter().map(|f| f.map(new_id)).collect();
    let mesh = Mesh::new(
        positions,
        faces,
        sheets.face_layers().to_vec(),
        sheets.layer_names().to_vec(),
    )
    .unwrap();
    let grid = slayer::grid::SpatialHash::build(&mesh, 0.05).unwrap();
    let active = [true, true, false];
    let state = StrokeState {
        grid: Some(&grid),
        active: &active,
        parallel: false,
        collision_distance: 0.05,
        ring: 2,
        max_edge: 0.08,
        cull: true,
    };
    let mut gpu_kernels = GpuKernels::new(gpu());
    let dab = |kind, radius| Dab {
        brush: Brush {
            kind,
            radius,
            strength: 0.6,
            falloff: Falloff::Smooth,
            invert: false,
        },
        frame: DabFrame {
            center: Vec3::new(3.0, 2.5, 0.1),
            normal: Vec3::new(0.2, 0.1, 1.0).normalize(),
            plane_point: Vec3::new(3.0, 2.5, 0.05),
            motion: Vec3::new(0.01, 0.0, 0.0),
        },
        pressure: 1.0,
        share: 1.0,
    };
    let own_normal = Some(Vec3::new(0.3, -0.1, 1.0).normalize());
    let calls = [
        (
            BrushKind::Flatten,
            0.2,
            FrameSource::Selection { normal: None },
            true,
        ),
        // Far past the guess: the list is read twice and deformed apart.
        (
            BrushKind::Flatten,
            1.9,
            FrameSource::Selection { normal: None },
            true,
        ),
        (
            BrushKind::Draw,
            1.9,
            FrameSource::Selection { normal: own_normal },
            true,
        ),
        (BrushKind::Draw, 0.25, FrameSource::Dab, true),
        (
            BrushKind::Paint,
            0.3,
            FrameSource::Selection { normal: None },
            false,
        ),
    ];
    for (k, &(kind, radius, source, deforms)) in calls.iter().enumerate() {
        let dab = dab(kind, radius);
        let read_backs = gpu_kernels.uploads().unwrap().read_backs;
        let on_gpu = gpu_kernels.select_and_deform(&state, &mesh, &dab, (source, deforms));
        let read_backs = gpu_kernels.uploads().unwrap().read_backs - read_backs;
        let on_cpu = CpuKernels.select_and_deform(&state, &mesh, &dab, (source, deforms));
        let label = format!("call {k}: {} radius {radius}", kind.name());
        assert!(gpu_kernels.failure().is_none(), "{label}: GPU gave up");
        assert!(
            on_cpu.selection.len() > 20,
            "{label}: selects {}",
            on_cpu.selection.len()
        );
        if rounds_as_the_cpu() {
            assert_eq!(on_gpu.selection, on_cpu.selection, "{label}: selection");
            assert_eq!(on_gpu.frame, on_cpu.frame, "{label}: frame");
        } else {
            let center = dab.frame.center;
            let reach = |v: u32| mesh.positions()[v as usize].distance(center) / radius;
            assert_selections_agree(&label, &on_gpu.selection, &on_cpu.selection, reach);
            let (g, c) = (on_gpu.frame, on_cpu.frame);
            let apart = [
                g.center.distance(c.center),
                g.normal.distance(c.normal) * radius,
                g.plane_point.distance(c.plane_point),
                g.motion.distance(c.motion),
            ];
            assert!(
                apart.iter().all(|&d| d <= 1e-5 * radius),
                "{label}: frames {g:?} and {c:?}"
            );
        }
        assert_eq!(on_gpu.targets.is_some(), deforms, "{label}: targets");
        if let (Some(g), Some(c)) = (&on_gpu.targets, &on_cpu.targets) {
            let worst = g
                .iter()
                .zip(c)
                .map(|(p, q)| p.distance(*q))
                .fold(0.0, f32::max);
            assert!(worst <= 1e-5 * radius, "{label}: targets {worst:e} apart");
        }
        // The first call builds the hash table (a wait, not a read-back); past the guess the
        // rest of the list and the deformation are two more.
        let expected = if k == 1 { 3 } else { 1 };
        assert_eq!(read_backs, expected, "{label}: read-backs");
    }
}

/// A fuse layer joined after a stroke on the GPU backend: the GPU's copy of the mesh follows
/// the topology change (faces cut out, a tube sewn in, remeshed), the next stroke runs on it,
/// and both end as on the CPU pipeline.
#[test]
fn a_topology_change_after_a_stroke_patches_the_gpu_copy() {
    use glam::Vec3;
    use slayer::brush::{BrushKind, StrokeSettings};
    let sphere = slayer::scene::geodesic_sphere(8, 1.0).unwrap();
    let fused = |kind: BrushKind, radius: f32, points: [Vec3; 2]| {
        let stroke = common::one_brush_stroke(kind, radius, &points);
        let settings = StrokeSettings {
            fuse: vec![0],
            ..stroke.settings()
        };
        (settings, stroke.samples)
    };
    let push = fused(BrushKind::Grab, 0.5, [Vec3::Y, Vec3::new(0.0, -1.3, 0.0)]);
    let draw = fused(BrushKind::Draw, 0.3, [Vec3::X, Vec3::new(0.9, 0.3, 0.0)]);
    let sculpt = |pipeline: &mut Pipeline, mesh: &mut Mesh| {
        let (settings, samples) = push.clone();
        let first = pipeline
            .begin_stroke(mesh, settings)
            .unwrap()
            .finish_with(&samples)
            .unwrap();
        assert_eq!(first.topology.joins, 1, "{:?}", first.topology);
        pipeline.check_kernel_copy(mesh).unwrap();
        let (settings, samples) = draw.clone();
        pipeline
            .begin_stroke(mesh, settings)
            .unwrap()
            .finish_with(&samples)
            .unwrap();
        pipeline.check_kernel_copy(mesh).unwrap();
    };
    let (on_gpu, pipeline) = sculpted_on_both(&sphere, sculpt);
    let uploads = pipeline.uploads().expect("GPU kernels keep a copy");
    assert_eq!(uploads.whole, 1, "patched, not sent again: {uploads:?}");
    let shapes = on_gpu.component_shapes();
    assert_eq!((shapes.len(), shapes[0].genus), (1, 1), "{shapes:?}");
}

/// A grab outside any fuse layer pushed into another layer and pulled back on the GPU backend:
/// the vertices collisions hold still are let go of and taken back as on the CPU pipeline (the
/// pipeline decides from the positions the GPU's clamp returns: one held exactly still there
/// must be exactly still here too), and the sheet comes back as far.
#[test]
fn a_grab_held_by_a_layer_lets_go_as_on_the_cpu_pipeline() {
    let (sheets, stroke) = common::grab_pushed_into_a_layer_and_back();
    let clamps = std::cell::RefCell::new(Vec::new());
    let sculpt = |pipeline: &mut Pipeline, mesh: &mut Mesh| {
        let report = pipeline.apply_stroke(mesh, &stroke).unwrap();
        clamps.borrow_mut().push(report.clamped);
    };
    let (on_gpu, _) = sculpted_on_both(&sheets, sculpt);
    // Clamps counted on the CPU, then on the GPU: a vertex let go of is not clamped again, so
    // a backend that let go of other vertices would count others (56 on both; 61 when
    // nothing is let go of).
    let clamps = clamps.into_inner();
    eprintln!("clamps: {clamps:?}");
    assert!(clamps[0] > 0, "the push never met the lower sheet");
    assert_eq!(clamps[0], clamps[1], "clamps on the CPU and on the GPU");
    let sunk = common::upper_sheet_sunk(&on_gpu);
    assert!(
        sunk < 60.0,
        "the upper sheet is left {sunk} below where it began"
    );
}

/// `start` sculpted by `sculpt` on the CPU pipeline and on the GPU kernels (every pass on the
/// GPU): the GPU's result is valid, crosses nothing and has the CPU's vertices within 1e-4·L.
/// Returns it, with the GPU pipeline.
fn sculpted_on_both(start: &Mesh, sculpt: impl Fn(&mut Pipeline, &mut Mesh)) -> (Mesh, Pipeline) {
    let mut on_cpu = start.clone();
    sculpt(&mut Pipeline::new(PipelineSettings::default()), &mut on_cpu);
    let mut on_gpu = start.clone();
    let mut pipeline = Pipeline::with_kernels(PipelineSettings::default(), Box::new(all_on_gpu()));
    sculpt(&mut pipeline, &mut on_gpu);
    assert_eq!(pipeline.kernel_failure(), None);
    on_gpu.validate().unwrap();
    assert_eq!(find_intersections(&on_gpu).total(), 0);
    assert_matches_cpu("sculpted", &on_cpu, &on_gpu, on_cpu.mean_edge_length());
    (on_gpu, pipeline)
}

/// Freestyle's brushes on the GPU backend: a volume-keeping sweep drawn off a sphere (its
/// correction runs in the pipeline on the targets the GPU deformed, and the proximity passes
/// the GPU ran ahead for the uncorrected targets are dropped) and a trim across it end as on the
/// CPU pipeline, the GPU's copy the mesh, the volume kept.
#[test]
fn the_sweeps_and_trim_on_the_gpu_match_the_cpu_pipeline() {
    use glam::Vec3;
    use slayer::brush::{BrushKind, Falloff, Stroke};
    let sphere = slayer::scene::geodesic_sphere(10, 1.0).unwrap();
    let volume = |mesh: &Mesh| mesh.closed_components()[0].volume;
    let stroke = |kind: BrushKind, points: [Vec3; 2]| -> Stroke {
        let mut stroke = common::one_brush_stroke(kind, 0.4, &points);
        stroke.brush.falloff = Falloff::Blend { n: 3, inner: 0.5 };
        stroke
    };
    let strokes = [
        stroke(BrushKind::SweepVolume, [Vec3::Z, Vec3::new(0.2, 0.0, 1.7)]),
        stroke(BrushKind::Sweep, [Vec3::X, Vec3::new(1.4, 0.3, 0.0)]),
        stroke(BrushKind::Trim, [Vec3::Y, Vec3::new(0.3, 0.95, 0.0)]),
    ];
    let sculpt = |pipeline: &mut Pipeline, mesh: &mut Mesh| {
        let before = volume(mesh);
        pipeline.apply_stroke(mesh, &strokes[0]).unwrap();
        let change = volume(mesh) / before - 1.0;
        assert!(change.abs() < 0.01, "volume {change:+.4}");
        for s in &strokes[1..] {
            pipeline.apply_stroke(mesh, s).unwrap();
        }
        pipeline.check_kernel_copy(mesh).unwrap();
    };
    sculpted_on_both(&sphere, sculpt);
}
