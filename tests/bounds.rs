//! Issue 22, item 1: work derived from input is bounded before it starts. Two samples far
//! apart, streamed or in a file, are refused with a clear error and leave the mesh alone; a
//! stroke whose remeshing would create more faces than its bound stops splitting there.

use std::time::{Duration, Instant};

use glam::Vec3;
use slayer::brush::{
    Brush, BrushKind, Falloff, MAX_STROKES, Resampler, Sample, Stroke, StrokeFile, StrokeSettings,
};
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineError, PipelineSettings};
use slayer::scene::{SceneKind, SceneSpec, generate};

fn plaster() -> Mesh {
    generate(&SceneSpec {
        kind: SceneKind::Plaster,
        triangles: 2_000,
        seed: 1,
    })
    .unwrap()
}

fn sample(x: f32, y: f32, z: f32) -> Sample {
    Sample {
        position: Vec3::new(x, y, z),
        pressure: 1.0,
        normal: None,
    }
}

fn settings(radius: f32) -> StrokeSettings {
    StrokeSettings {
        brush: Brush {
            kind: BrushKind::Draw,
            radius,
            strength: 0.5,
            falloff: Falloff::default(),
            invert: true,
        },
        paint: None,
        layers: vec![1],
        spacing: 0.25,
        symmetry: None,
        fuse: Vec::new(),
    }
}

/// The issue's stroke: `[-0.26, 0.43, 0]` then `[1e17, 0, 0]` at radius 0.05 resampled into
/// dabs without end; now it is refused at once and the mesh is as it was.
#[test]
fn two_far_samples_are_refused_before_any_dab() {
    let mut mesh = plaster();
    let before = mesh.positions().to_vec();
    let stroke = Stroke {
        samples: vec![sample(-0.26, 0.43, 0.0), sample(1e17, 0.0, 0.0)],
        ..stroke_of(settings(0.05))
    };
    let started = Instant::now();
    let result = Pipeline::new(PipelineSettings::default()).apply_stroke(&mut mesh, &stroke);
    assert!(
        started.elapsed() < Duration::from_secs(5),
        "refused at once"
    );
    match result {
        Err(PipelineError::TooManyDabs(limit)) => {
            assert_eq!(limit.limit, slayer::brush::MAX_DABS_PER_STROKE);
            assert!(limit.wanted > 1e18, "{limit:?}");
            let message = limit.to_string();
            assert!(message.contains("--max-dabs"), "{message}");
            assert!(message.contains("100000 allowed"), "{message}");
        }
        other => panic!("expected TooManyDabs, got {other:?}"),
    }
    assert_eq!(mesh.positions(), &before[..], "the mesh is untouched");
}

fn stroke_of(settings: StrokeSettings) -> Stroke {
    Stroke {
        brush: settings.brush,
        paint: settings.paint,
        layers: settings.layers,
        spacing: settings.spacing,
        symmetry: None,
        samples: Vec::new(),
    }
}

/// A streamed stroke has the same bound: a call whose samples would pass it is refused whole,
/// runs none of its samples, and the stroke goes on afterwards.
#[test]
fn a_streamed_stroke_refuses_samples_past_its_bound_and_goes_on() {
    let mut mesh = plaster();
    let mut pipeline = Pipeline::new(PipelineSettings {
        max_dabs_per_stroke: 40,
        ..PipelineSettings::default()
    });
    let mut stroke = pipeline.begin_stroke(&mut mesh, settings(0.1)).unwrap();
    let near = [sample(0.3, 0.5, 0.15), sample(0.35, 0.5, 0.15)];
    let first = stroke.add_samples(&near).unwrap();
    assert!(first.samples > 0);
    let before = stroke.mesh().positions().to_vec();
    // 0.025 per dab: 2 units is 80 dabs, past the bound of 40; a near sample comes first in
    // the same call and must not run either.
    let refused = stroke.add_samples(&[sample(0.4, 0.5, 0.15), sample(2.4, 0.5, 0.15)]);
    match refused {
        Err(PipelineError::TooManyDabs(limit)) => assert_eq!(limit.limit, 40),
        other => panic!("expected TooManyDabs, got {other:?}"),
    }
    assert_eq!(stroke.mesh().positions(), &before[..], "nothing ran");
    let again = stroke.add_samples(&[sample(0.45, 0.5, 0.15)]).unwrap();
    assert!(again.samples > 0, "the stroke goes on from where it was");
    let report = stroke.finish().unwrap();
    assert!(report.samples <= 40, "{}", report.samples);
}

/// The resampler itself: a push past the bound emits nothing and leaves it as it was, and a
/// stroke never emits more than the bound, its last sample included.
#[test]
fn the_resampler_never_emits_past_its_bound() {
    let mut resampler = Resampler::with_limit(0.1, 25);
    let mut out = Vec::new();
    resampler.push(sample(0.0, 0.0, 0.0), &mut out).unwrap();
    assert!(resampler.push(sample(1e17, 0.0, 0.0), &mut out).is_err());
    assert_eq!(out.len(), 1, "the refused push emitted nothing");
    let mut x = 0.0;
    while resampler.push(sample(x + 0.35, 0.0, 0.0), &mut out).is_ok() {
        x += 0.35;
    }
    resampler.finish(&mut out);
    assert!(out.len() <= 25, "{}", out.len());
    assert!(
        out.len() >= 20,
        "the bound is used, not feared: {}",
        out.len()
    );
    let end = out.last().unwrap().position.x;
    assert!(
        (end - x).abs() < 1e-3,
        "ends on the last accepted sample: {end} {x}"
    );
}

/// A stroke file holds at most MAX_STROKES strokes; more is refused by the parser, in words.
#[test]
fn a_stroke_file_with_too_many_strokes_is_refused() {
    let one = r#"{"brush": "draw", "radius": 0.1, "strength": 0.5, "layers": [0], "samples": [{"position": [0, 0, 0]}]}"#;
    let text = format!(
        r#"{{"strokes": [{}]}}"#,
        vec![one; MAX_STROKES + 1].join(",")
    );
    let error = StrokeFile::parse(&text, "many.json")
        .unwrap_err()
        .to_string();
    assert!(
        error.contains(&format!("{} strokes", MAX_STROKES + 1)),
        "{error}"
    );
    assert!(error.contains(&MAX_STROKES.to_string()), "{error}");
}

/// Settings built in code (as the app builds them) get the stroke file's brush checks when the
/// stroke begins: an absurd radius, strength or spacing is refused by name, and nothing runs.
#[test]
fn absurd_brush_settings_are_refused_when_the_stroke_begins() {
    let mut mesh = plaster();
    let before = mesh.digest();
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    let mut cases: Vec<(StrokeSettings, &str)> = vec![
        (settings(f32::NAN), "brush.radius"),
        (settings(-0.1), "brush.radius"),
        (settings(1e6), "times the mesh's size"),
    ];
    let mut strong = settings(0.2);
    strong.brush.strength = 40.0;
    cases.push((strong, "brush.strength"));
    let mut sparse = settings(0.2);
    sparse.spacing = 0.0;
    cases.push((sparse, "brush.spacing"));
    for (bad, expected) in cases {
        match pipeline.begin_stroke(&mut mesh, bad) {
            Err(PipelineError::InvalidBrush(message)) => {
                assert!(message.contains(expected), "{message}")
            }
            Err(other) => panic!("{other}"),
            Ok(_) => panic!("accepted a brush that should name {expected}"),
        }
    }
    assert_eq!(mesh.digest(), before);
    // The pipeline is still ready for a sane stroke.
    let mut stroke = pipeline.begin_stroke(&mut mesh, settings(0.2)).unwrap();
    stroke.add_samples(&[sample(0.0, 0.0, 0.0)]).unwrap();
    stroke.finish().unwrap();
}

/// A sample whose move needs more than `MAX_STEPS_PER_SAMPLE` steps (here a draw over steps
/// of a thousandth of an edge: over 400 needed) moves that many steps, none longer than the step
/// limit, and is counted, not cut silently.
#[test]
fn a_runaway_sample_moves_its_most_steps_each_within_the_limit_and_is_counted() {
    use slayer::pipeline::step::MAX_STEPS_PER_SAMPLE;
    let mut mesh = slayer::scene::shapes::stacked_sheets(1, 30, 30, 1.0, 0.0);
    let start = mesh.clone();
    let mut stroke = stroke_of(StrokeSettings {
        layers: vec![0],
        ..settings(6.0)
    });
    stroke.brush.strength = 0.8;
    stroke.brush.invert = false;
    stroke.samples = vec![Sample {
        normal: Some(Vec3::Z),
        ..sample(15.0, 15.0, 0.0)
    }];
    let max_step = 0.001;
    let mut pipeline = Pipeline::new(PipelineSettings {
        max_step,
        remeshing: slayer::pipeline::Remeshing::Off,
        ..PipelineSettings::default()
    });
    let report = pipeline.apply_stroke(&mut mesh, &stroke).unwrap();
    assert_eq!(report.capped_samples, 1, "{report:?}");
    assert_eq!(report.steps, MAX_STEPS_PER_SAMPLE);
    // The centre would rise 0.1 · 6 · 0.8 = 0.48; it rises 256 steps of at most 0.001 L.
    let edge = pipeline.edge_length().unwrap();
    let limit = MAX_STEPS_PER_SAMPLE as f32 * max_step * edge * 1.0001;
    let centre = 15 * 31 + 15;
    let rise = mesh.positions()[centre].z - start.positions()[centre].z;
    assert!(rise > 0.2 && rise <= limit, "rose {rise}");
    let farthest = mesh
        .positions()
        .iter()
        .zip(start.positions())
        .map(|(p, q)| p.distance(*q))
        .fold(0.0f32, f32::max);
    assert!(farthest <= limit, "a vertex moved {farthest}");
}

/// A grab pulling a tall tent out of a sheet of 392 faces whose remeshing would create
/// hundreds more: with a bound of 400 new faces it creates at most 400, says so, and
/// leaves a valid mesh with edges long where it stopped; the default bound lets the same
/// stroke create more, so the bound is what stopped it.
#[test]
fn a_stroke_creates_at_most_its_bound_of_new_faces() {
    let tent = |new_faces_per_stroke: usize| {
        let mut mesh = slayer::scene::shapes::stacked_sheets(1, 14, 14, 1.0, 0.0);
        let mut stroke = stroke_of(StrokeSettings {
            layers: vec![0],
            ..settings(5.0)
        });
        stroke.brush.kind = BrushKind::Grab;
        stroke.brush.strength = 1.0;
        stroke.samples = (0..4).map(|i| sample(7.0, 7.0, 4.0 * i as f32)).collect();
        let mut pipeline = Pipeline::new(PipelineSettings {
            new_faces_per_stroke,
            ..PipelineSettings::default()
        });
        let faces = mesh.live_face_count();
        let report = pipeline.apply_stroke(&mut mesh, &stroke).unwrap();
        mesh.validate().unwrap();
        (report, faces, mesh)
    };
    let (report, faces_before, mesh) = tent(400);
    assert!(report.remesh.growth_capped > 0, "{:?}", report.remesh);
    assert!(report.remesh.splits <= 200, "{:?}", report.remesh);
    let created = mesh.live_face_count().saturating_sub(faces_before);
    assert!(
        created <= 400,
        "{faces_before} → {} faces",
        mesh.live_face_count()
    );
    assert_eq!(slayer::collide::find_intersections(&mesh).total(), 0);
    let (unbounded, _, remeshed) = tent(slayer::pipeline::NEW_FACES_PER_STROKE);
    let split_above = slayer::remesh::SPLIT_ABOVE; // × L, which is 1 here
    assert!(
        mesh.longest_edge() > 1.2 * split_above && remeshed.longest_edge() < mesh.longest_edge(),
        "edges left long: {} (all split: {})",
        mesh.longest_edge(),
        remeshed.longest_edge()
    );
    assert_eq!(unbounded.remesh.growth_capped, 0, "{:?}", unbounded.remesh);
    assert!(
        unbounded.remesh.splits > 200,
        "the default bound lets it split more: {:?}",
        unbounded.remesh
    );
}

/// Soak stroke sphere #868 in small: a sweep of twice a closed sphere's size (the most a brush
/// may be) drags it far, smearing it into slivers. The step that stretches an edge past the stroke's bound
/// is its last: what it did is kept (valid, nothing crossing), the samples streamed after it
/// run nothing, and the report says how far it stretched. A bound four times higher lets the
/// same stroke run longer, so the bound is what stopped it.
#[test]
fn a_stroke_that_stretches_an_edge_past_its_bound_stops_there() {
    let smear = |max_stretch: f32| {
        let mut mesh = generate(&SceneSpec {
            kind: SceneKind::Sphere,
            triangles: 2_000,
            seed: 1,
        })
        .unwrap();
        let (lo, hi) = mesh.bounds().unwrap();
        let (centre, size) = ((lo + hi) / 2.0, (hi - lo).max_element());
        let mut sweep = settings(1.9 * size);
        (sweep.brush.kind, sweep.brush.strength, sweep.layers) = (BrushKind::Sweep, 0.32, vec![0]);
        let mut pipeline = Pipeline::new(PipelineSettings {
            max_stretch,
            ..PipelineSettings::default()
        });
        let path = |t: f32| {
            let at = centre + Vec3::new(size * (1.0 - 20.0 * t), size * 0.8 * t, 0.0);
            sample(at.x, at.y, at.z)
        };
        let mut stroke = pipeline.begin_stroke(&mut mesh, sweep).unwrap();
        let first = stroke.add_samples(&[path(0.0), path(0.5)]).unwrap();
        let later = stroke.add_samples(&[path(0.75), path(1.0)]).unwrap();
        let report = stroke.finish().unwrap();
        mesh.validate().unwrap();
        assert_eq!(slayer::collide::find_intersections(&mesh).total(), 0);
        (first, later, report)
    };
    let (first, later, report) = smear(8.0);
    let stretched = first.stopped_stretched.expect("stopped in the first call");
    assert!(stretched > 8.0, "{stretched}");
    assert_eq!(report.stopped_stretched, Some(stretched));
    assert_eq!((later.samples, later.steps), (0, 0), "{later:?}");
    assert!(report.steps > 0 && report.touched > 0, "{report:?}");
    let (_, _, longer) = smear(32.0);
    assert!(
        longer.steps > report.steps,
        "a higher bound runs on: {} steps against {}",
        longer.steps,
        report.steps
    );
}
