//! Strokes fed as they are drawn: the same stroke given to `StrokeInProgress::add_samples` one
//! sample at a time, three at a time, or all at once must sculpt the same mesh — bit for bit on
//! the CPU backend, within the parity tolerance on the GPU backend (lavapipe in CI, never
//! skipped), where the samples of one call may run ahead in one submission.

use proptest::prelude::*;
use slayer::bench::{Feed, ScriptSpec, feed_stroke, generate_script};
use slayer::brush::{Resampler, Sample, Stroke, resample};
use slayer::collide::find_intersections;
use slayer::gpu::{GpuContext, GpuKernels, GpuOptions};
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings, Remeshing, SamplesReport};
use slayer::scene::{SceneKind, SceneSpec, generate};

/// A small plaster scene and `count` strokes of the bench's script (every brush it mixes,
/// many pressing one layer into another) from `seed`.
fn plaster_and_strokes(faces: usize, count: usize, seed: u64) -> (Mesh, Vec<Stroke>) {
    let mesh = generate(&SceneSpec {
        kind: SceneKind::Plaster,
        triangles: faces,
        seed: 3,
    })
    .unwrap();
    let script = generate_script(
        &mesh,
        &ScriptSpec {
            strokes: count,
            seed,
            ..ScriptSpec::default()
        },
    );
    let strokes = script.resolve(&mesh, "script").unwrap();
    (mesh, strokes)
}

/// Everything a stroke can change, compared exactly.
fn assert_identical(a: &Mesh, b: &Mesh, what: &str) {
    assert_eq!(a.vertex_count(), b.vertex_count(), "{what}: vertex count");
    assert_eq!(a.faces(), b.faces(), "{what}: faces");
    assert_eq!(a.face_layers(), b.face_layers(), "{what}: face layers");
    assert_eq!(
        a.vertex_layers(),
        b.vertex_layers(),
        "{what}: vertex layers"
    );
    assert_eq!(a.flags(), b.flags(), "{what}: flags");
    // Bits, not values: -0.0 against 0.0 or two NaNs would hide a difference.
    let bits = |m: &Mesh| -> Vec<u32> {
        m.positions()
            .iter()
            .chain(m.normals())
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert!(bits(a) == bits(b), "{what}: positions or normals differ");
    assert!(a.brdfs() == b.brdfs(), "{what}: BRDFs differ");
}

/// Sculpts `strokes` on a copy of `start`, each fed `samples_per_call` samples per call.
fn sculpt(
    pipeline: &mut Pipeline,
    start: &Mesh,
    strokes: &[Stroke],
    samples_per_call: Option<usize>,
) -> Mesh {
    let mut mesh = start.clone();
    for stroke in strokes {
        feed_stroke(
            pipeline,
            &mut mesh,
            stroke,
            Feed {
                samples_per_call,
                fuse: false,
            },
        )
        .unwrap();
    }
    mesh
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    /// On the CPU backend, with remeshing after every stroke: random strokes give the same
    /// mesh bit for bit whether fed 1, 3 or all samples per call.
    #[test]
    fn cpu_strokes_fed_in_any_chunks_sculpt_the_same_mesh(seed in 0u64..1000, chunk in 2usize..6) {
        let (start, strokes) = plaster_and_strokes(3_000, 4, seed);
        let settings = PipelineSettings::default();
        let whole = sculpt(&mut Pipeline::new(settings), &start, &strokes, None);
        for per_call in [1, chunk] {
            let fed = sculpt(&mut Pipeline::new(settings), &start, &strokes, Some(per_call));
            assert_identical(&whole, &fed, &format!("{per_call} samples per call"));
        }
        whole.validate().unwrap();
        prop_assert_eq!(find_intersections(&whole).total(), 0);
    }
}

/// A stroke's samples run on a thread of rayon's pool, whoever calls: from outside any pool,
/// from the only thread of a one-thread pool (run where it is), or from a pool of three, the
/// CPU backend sculpts the same mesh bit for bit, and none of them waits on a thread it
/// occupies itself.
#[test]
fn strokes_sculpt_the_same_mesh_whatever_thread_calls() {
    let (start, strokes) = plaster_and_strokes(3_000, 4, 17);
    let settings = PipelineSettings::default();
    let outside = sculpt(&mut Pipeline::new(settings), &start, &strokes, Some(2));
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let inside =
            pool.install(|| sculpt(&mut Pipeline::new(settings), &start, &strokes, Some(2)));
        assert_identical(&outside, &inside, &format!("called in a pool of {threads}"));
    }
    assert!(
        outside.positions() != start.positions(),
        "the strokes moved nothing"
    );
    outside.validate().unwrap();
}

/// The resampler emits the same samples whatever the chunks it is fed in, and the same as
/// `resample` over the whole polyline.
#[test]
fn resampling_across_calls_matches_resampling_the_whole() {
    let (_, strokes) = plaster_and_strokes(2_000, 6, 11);
    for stroke in &strokes {
        let step = stroke.settings().resampling_step();
        let whole = resample(&stroke.samples, step).unwrap();
        for per_call in [1, 2, 5] {
            let mut resampler = Resampler::new(step);
            let mut out: Vec<Sample> = Vec::new();
            for chunk in stroke.samples.chunks(per_call) {
                for &s in chunk {
                    resampler.push(s, &mut out).unwrap();
                }
            }
            resampler.finish(&mut out);
            assert_eq!(out, whole, "{per_call} per call");
        }
    }
}

/// Each call reports the vertices it changed: every vertex whose position or normal differs
/// from before the call is among them, and the last sample given waits for the next call.
#[test]
fn each_call_reports_the_vertices_it_changed() {
    let (start, strokes) = plaster_and_strokes(2_000, 3, 5);
    let settings = PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    };
    let mut pipeline = Pipeline::new(settings);
    let mut mesh = start.clone();
    let mut moved_any = false;
    for stroke in &strokes {
        let mut in_progress = pipeline.begin_stroke(&mut mesh, stroke.settings()).unwrap();
        for samples in stroke.samples.chunks(2) {
            let before = in_progress.mesh().clone();
            let report: SamplesReport = in_progress.add_samples(samples).unwrap();
            let after = in_progress.mesh();
            for v in 0..after.vertex_count() as u32 {
                let i = v as usize;
                let differs = before.positions()[i] != after.positions()[i]
                    || before.normals()[i] != after.normals()[i];
                if differs {
                    moved_any = true;
                    assert!(
                        report.changed.binary_search(&v).is_ok(),
                        "vertex {v} unreported"
                    );
                }
            }
            assert!(report.changed.windows(2).all(|w| w[0] < w[1]));
        }
        in_progress.finish().unwrap();
    }
    assert!(moved_any, "the strokes move something");
}

/// `finish` reports what its last sample and the remeshing after the stroke changed: every
/// vertex whose position, normal or faces differ from before `finish` is listed, new ones too.
#[test]
fn finish_reports_what_remeshing_changed() {
    let (start, strokes) = plaster_and_strokes(2_000, 3, 5);
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    let mut mesh = start.clone();
    let mut remeshed_any = false;
    for stroke in &strokes {
        let mut in_progress = pipeline.begin_stroke(&mut mesh, stroke.settings()).unwrap();
        in_progress.add_samples(&stroke.samples).unwrap();
        let before = in_progress.mesh().clone();
        let report = in_progress.finish().unwrap();
        remeshed_any |= report.remesh.splits + report.remesh.collapses + report.remesh.flips > 0;
        assert!(report.changed.windows(2).all(|w| w[0] < w[1]));
        for v in 0..mesh.vertex_count() as u32 {
            let i = v as usize;
            let differs = i >= before.vertex_count()
                || before.positions()[i] != mesh.positions()[i]
                || before.normals()[i] != mesh.normals()[i]
                || before.is_vertex_dead(v) != mesh.is_vertex_dead(v);
            if differs {
                assert!(
                    report.changed.binary_search(&v).is_ok(),
                    "vertex {v} unreported"
                );
            }
        }
    }
    assert!(remeshed_any, "the strokes are remeshed");
}

/// A stroke dropped before `finish` leaves the pipeline ready: the next stroke runs, and the
/// mesh stays sound.
#[test]
fn a_stroke_dropped_unfinished_leaves_the_pipeline_ready() {
    let (start, strokes) = plaster_and_strokes(2_000, 2, 8);
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    let mut mesh = start.clone();
    {
        let mut in_progress = pipeline
            .begin_stroke(&mut mesh, strokes[0].settings())
            .unwrap();
        let half = strokes[0].samples.len() / 2;
        in_progress
            .add_samples(&strokes[0].samples[..half.max(1)])
            .unwrap();
    }
    pipeline.apply_stroke(&mut mesh, &strokes[1]).unwrap();
    mesh.validate().unwrap();
    assert_eq!(find_intersections(&mesh).total(), 0);
}

fn gpu_pipeline(settings: PipelineSettings, options: &GpuOptions) -> Pipeline {
    let gpu = GpuContext::open(options)
        .unwrap_or_else(|e| panic!("GPU tests need an adapter (run tools/test.sh): {e}"));
    Pipeline::with_kernels(settings, Box::new(GpuKernels::with_options(gpu, options)))
}

/// The largest distance between the same vertex of two meshes.
fn largest_deviation(a: &Mesh, b: &Mesh) -> f32 {
    a.positions()
        .iter()
        .zip(b.positions())
        .map(|(p, q)| p.distance(*q))
        .fold(0.0f32, f32::max)
}

/// Sculpts `strokes` on the GPU backend with `options`, fed each of `chunkings` samples per
/// call, and checks every result against the CPU pipeline's and the first chunking's within
/// the parity tolerance (1e-4·L). Returns the blocking read-backs of each chunking.
fn check_gpu_chunks(
    options: &GpuOptions,
    (start, strokes): (&Mesh, &[Stroke]),
    chunkings: &[Option<usize>],
) -> Vec<usize> {
    let edge = start.mean_edge_length();
    // Without remeshing the meshes keep their vertices and compare one by one.
    let settings = PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    };
    let on_cpu = sculpt(&mut Pipeline::new(settings), start, strokes, None);
    let mut read_backs = Vec::new();
    let mut first: Option<Mesh> = None;
    for &per_call in chunkings {
        let mut pipeline = gpu_pipeline(settings, options);
        let mesh = sculpt(&mut pipeline, start, strokes, per_call);
        assert_eq!(pipeline.kernel_failure(), None);
        pipeline.check_kernel_copy(&mesh).unwrap();
        let uploads = pipeline.uploads().expect("GPU kernels keep a copy");
        let deviation = largest_deviation(&on_cpu, &mesh);
        eprintln!(
            "{per_call:?} samples per call: deviation from the cpu {:.2e} L, {uploads:?}",
            deviation / edge
        );
        assert!(
            deviation <= 1e-4 * edge,
            "{per_call:?}: {deviation} > 1e-4 L"
        );
        let from_first = first.as_ref().map_or(0.0, |f| largest_deviation(f, &mesh));
        assert!(
            from_first <= 1e-4 * edge,
            "{per_call:?}: {from_first} from the first"
        );
        assert_eq!(find_intersections(&mesh).total(), 0);
        read_backs.push(uploads.read_backs);
        first.get_or_insert(mesh);
    }
    read_backs
}

/// The GPU backend as it runs on lavapipe by default (selection and deformation on the GPU,
/// the collision response on the CPU): strokes fed 1, 3 or all samples per call agree.
#[test]
fn gpu_strokes_fed_in_any_chunks_sculpt_the_same_mesh() {
    let (start, strokes) = plaster_and_strokes(2_000, 3, 21);
    let chunkings = [None, Some(3), Some(1)];
    check_gpu_chunks(&GpuOptions::default(), (&start, &strokes), &chunkings);
}

/// Everything on the GPU and the samples of a call run ahead in one submission behind the
/// gate: the batch and one sample per call agree, and the batch reads back less.
#[test]
fn gpu_runs_of_the_samples_given_agree_with_one_sample_per_call() {
    let (start, strokes) = plaster_and_strokes(800, 2, 21);
    let options = GpuOptions {
        proximity_on_gpu: Some(true),
        runs_ahead: Some(true),
        ..GpuOptions::default()
    };
    let read_backs = check_gpu_chunks(&options, (&start, &strokes), &[None, Some(1)]);
    assert!(
        read_backs[0] < read_backs[1],
        "the batch reads back less than one sample per call: {read_backs:?}"
    );
}

/// The app keeps one pipeline and opens one file after another. A pipeline fixes its edge
/// length once known: after `forget_mesh`, a pipeline that prepared for a plaster sculpts the
/// same plaster ten times larger exactly as a fresh pipeline does, on the CPU and on the GPU.
/// (Before mesh versions were process-wide stamps, two meshes could also share a version, and
/// the grid and GPU copy of the first then passed for the second's.)
#[test]
fn a_pipeline_that_forgets_its_mesh_sculpts_the_next_as_a_fresh_one() {
    let cpu = || Pipeline::new(PipelineSettings::default());
    let gpu = || gpu_pipeline(PipelineSettings::default(), &GpuOptions::default());
    for (backend, make) in [("cpu", &cpu as &dyn Fn() -> Pipeline), ("gpu", &gpu)] {
        let (first, _) = plaster_and_strokes(2000, 0, 1);
        let (mut next, _) = plaster_and_strokes(2000, 0, 1);
        next.positions_mut().iter_mut().for_each(|p| *p *= 10.0);
        assert_ne!(
            first.version(),
            next.version(),
            "each mesh's versions are its own"
        );
        let spec = ScriptSpec {
            strokes: 3,
            seed: 1,
            ..ScriptSpec::default()
        };
        let strokes = generate_script(&next, &spec)
            .resolve(&next, "script")
            .unwrap();
        let sculpt = |pipeline: &mut Pipeline| {
            let mut mesh = next.clone();
            for stroke in &strokes {
                pipeline.apply_stroke(&mut mesh, stroke).unwrap();
            }
            mesh
        };
        let mut fresh = make();
        let expected = sculpt(&mut fresh);
        let mut reused = make();
        reused.prepare(&first).unwrap();
        let first_edge = reused.edge_length();
        reused.forget_mesh();
        assert_identical(&sculpt(&mut reused), &expected, backend);
        assert_eq!(reused.edge_length(), fresh.edge_length(), "{backend}");
        assert_ne!(reused.edge_length(), first_edge, "{backend}");
    }
}
