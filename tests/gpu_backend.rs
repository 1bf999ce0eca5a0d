//! The pipeline with the GPU's selection, deformation and proximity passes (lavapipe in CI, never
//! skipped) against the CPU pipeline on the same strokes: positions, collision counts,
//! soundness, and the fallback to the CPU when the GPU is lost mid-stroke.

use slayer::bench::{ScriptSpec, generate_script};
use slayer::collide::find_intersections;
use slayer::gpu::{AdapterChoice, GpuContext, GpuKernels, PackedTopology};
use slayer::mesh::Mesh;
use slayer::pipeline::{CpuPipeline, PipelineSettings, Remeshing, SculptPipeline, Uploads};
use slayer::scene::{SceneKind, SceneSpec, generate};

fn gpu() -> GpuContext {
    GpuContext::new(AdapterChoice {
        allow_software: true,
    })
    .unwrap_or_else(|e| panic!("GPU tests need an adapter (run tools/test.sh): {e}"))
}

/// GPU kernels with every step kernel on the GPU, proximity passes included (a software
/// adapter leaves those on the CPU by default).
fn all_on_gpu() -> GpuKernels {
    let mut kernels = GpuKernels::new(gpu());
    kernels.set_proximity_on_gpu(true);
    kernels
}

/// The plaster scene, remeshed once to its mean edge as sculpting keeps it: the generated
/// scene has a few edges 3.5 times the mean around its holes, and the broad phase's reach
/// (and the GPU's work per moving vertex, cubed) follows the longest edge.
fn plaster_and_strokes(strokes: usize) -> (Mesh, Vec<slayer::brush::Stroke>) {
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
            strokes,
            seed: 9,
            ..ScriptSpec::default()
        },
    );
    let strokes = script.resolve(&mesh, "script").unwrap();
    (mesh, strokes)
}

/// Runs `strokes` and returns the collision count.
fn run(pipeline: &mut CpuPipeline, mesh: &mut Mesh, strokes: &[slayer::brush::Stroke]) -> usize {
    strokes
        .iter()
        .map(|s| pipeline.apply_stroke(mesh, s).unwrap().clamped)
        .sum()
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
    let (start, strokes) = plaster_and_strokes(5);
    let edge = start.mean_edge_length();
    // Without remeshing the two meshes keep the same vertices and can be compared one by one.
    let settings = PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    };
    let (mut on_cpu, mut on_gpu) = (start.clone(), start.clone());
    let cpu_collisions = run(&mut CpuPipeline::new(settings), &mut on_cpu, &strokes);
    let mut gpu_pipeline = CpuPipeline::with_kernels(settings, Box::new(all_on_gpu()));
    let gpu_collisions = run(&mut gpu_pipeline, &mut on_gpu, &strokes);
    assert_eq!(gpu_pipeline.kernel_failure(), None);
    let deviation = largest_deviation(&on_cpu, &on_gpu);
    eprintln!(
        "max deviation {deviation:e} ({:.2e} L), collisions cpu {cpu_collisions} gpu {gpu_collisions}",
        deviation / edge
    );
    assert!(deviation <= 1e-4 * edge, "{deviation} > 1e-4 L");
    assert!(cpu_collisions > 0, "the strokes collide");
    let spread = (cpu_collisions as f64 - gpu_collisions as f64).abs() / cpu_collisions as f64;
    assert!(spread <= 0.005, "{cpu_collisions} vs {gpu_collisions}");
    for mesh in [&on_cpu, &on_gpu] {
        mesh.validate().unwrap();
        assert_eq!(find_intersections(mesh).total(), 0);
    }
}

/// With remeshing after every stroke the GPU's copy is patched where remeshing changed the mesh
/// (rows of changed vertices, their neighbours and faces), never sent whole again, and after
/// every stroke it is the mesh row for row; the strokes give what the CPU pipeline gives.
#[test]
fn gpu_kernels_with_remeshing_patch_their_copy_and_keep_the_mesh_sound() {
    let (start, strokes) = plaster_and_strokes(3);
    let settings = PipelineSettings::default();
    let mut on_cpu = start.clone();
    let cpu_collisions = run(&mut CpuPipeline::new(settings), &mut on_cpu, &strokes);
    let mut mesh = start.clone();
    let mut pipeline = CpuPipeline::with_kernels(settings, Box::new(all_on_gpu()));
    let mut gpu_collisions = 0;
    for stroke in &strokes {
        let report = pipeline.apply_stroke(&mut mesh, stroke).unwrap();
        assert!(
            report.remesh.splits + report.remesh.collapses > 0,
            "remeshing edits"
        );
        gpu_collisions += report.clamped;
        pipeline.check_kernel_copy(&mesh).unwrap();
    }
    assert_eq!(pipeline.kernel_failure(), None);
    assert_eq!(
        pipeline.uploads(),
        Some(Uploads {
            whole: 1,
            patched: strokes.len()
        })
    );
    assert!(
        mesh.vertex_count() > start.vertex_count(),
        "remeshing added vertices"
    );
    assert_eq!(mesh.vertex_count(), on_cpu.vertex_count());
    let deviation = largest_deviation(&on_cpu, &mesh);
    assert!(deviation <= 1e-4 * start.mean_edge_length(), "{deviation}");
    assert_eq!(cpu_collisions, gpu_collisions);
    mesh.validate().unwrap();
    assert_eq!(find_intersections(&mesh).total(), 0);
}

/// A GPU lost in the middle of a stroke: the stroke finishes on the CPU, the failure is
/// reported, and the result is what the CPU alone makes.
#[test]
fn a_gpu_lost_mid_stroke_finishes_on_the_cpu() {
    let (start, strokes) = plaster_and_strokes(2);
    let settings = PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    };
    let mut on_cpu = start.clone();
    run(&mut CpuPipeline::new(settings), &mut on_cpu, &strokes);
    let mut kernels = all_on_gpu();
    kernels.fail_after(7);
    let mut pipeline = CpuPipeline::with_kernels(settings, Box::new(kernels));
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
    let (start, strokes) = plaster_and_strokes(1);
    let settings = PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    };
    let mut on_cpu = start.clone();
    run(&mut CpuPipeline::new(settings), &mut on_cpu, &strokes);
    let mut gpu = gpu();
    let needed = slayer::gpu::resident_bytes(&start);
    assert!(needed > 100_000, "{needed} bytes");
    gpu.budget_bytes = needed / 2;
    let mut kernels = GpuKernels::new(gpu);
    kernels.set_proximity_on_gpu(true);
    let mut pipeline = CpuPipeline::with_kernels(settings, Box::new(kernels));
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
    let (start, strokes) = plaster_and_strokes(2);
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
    let cpu_collisions = run(&mut CpuPipeline::new(settings), &mut on_cpu, &strokes);
    let mut kernels = GpuKernels::new(gpu);
    kernels.set_proximity_on_gpu(true);
    let mut pipeline = CpuPipeline::with_kernels(settings, Box::new(kernels));
    let mut mesh = start.clone();
    let gpu_collisions = run(&mut pipeline, &mut mesh, &strokes);
    assert_eq!(pipeline.kernel_failure(), None);
    let deviation = largest_deviation(&on_cpu, &mesh);
    assert!(deviation <= 1e-4 * start.mean_edge_length(), "{deviation}");
    assert_eq!(cpu_collisions, gpu_collisions);
    assert!(cpu_collisions > 0, "the strokes collide");
}
