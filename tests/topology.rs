//! Self-adaptive topology (the fuse policy): parts of one layer that touch join, necks split,
//! and the surface stays closed, manifold and free of intersections; collide layers never
//! change genus.

mod common;

use glam::Vec3;
use slayer::brush::{BrushKind, StrokeSettings};
use slayer::collide::find_intersections;
use slayer::grid::SpatialHash;
use slayer::mesh::{ComponentShape, Mesh};
use slayer::pipeline::{Pipeline, PipelineSettings, StrokeReport};
use slayer::scene::geodesic_sphere;
use slayer::topology::{FuseSettings, TopologyReport, adapt};

/// Spheres of `radius` at `centres`, all on one layer named "blob".
fn spheres(frequency: u32, radius: f32, centres: &[Vec3]) -> Mesh {
    let one = geodesic_sphere(frequency, radius).expect("sphere");
    let (mut positions, mut faces) = (Vec::new(), Vec::new());
    for &c in centres {
        let base = positions.len() as u32;
        positions.extend(one.positions().iter().map(|&p| p + c));
        faces.extend(one.faces().iter().map(|t| t.map(|v| v + base)));
    }
    let layers = vec![0; faces.len()];
    Mesh::new(positions, faces, layers, vec!["blob".into()]).expect("spheres")
}

/// Two spheres of radius 0.5 whose centres are `apart` along x, the first on layer "flake",
/// the second on layer "plaster".
fn flake_and_plaster(apart: f32) -> Mesh {
    let one = spheres(8, 0.5, &[Vec3::ZERO, Vec3::new(apart, 0.0, 0.0)]);
    let half = one.faces().len() / 2;
    let layers: Vec<u32> = (0..one.faces().len()).map(|f| (f >= half) as u32).collect();
    let names = vec!["flake".into(), "plaster".into()];
    Mesh::new(
        one.positions().to_vec(),
        one.faces().to_vec(),
        layers,
        names,
    )
    .expect("two layers")
}

/// Runs the fuse pass over every vertex of a one-layer mesh.
fn fuse_everywhere(mesh: &mut Mesh) -> TopologyReport {
    let edge = mesh.mean_edge_length();
    let settings = FuseSettings::new(mesh, edge, edge);
    let mut grid = SpatialHash::build(mesh, edge).expect("grid");
    let all: Vec<u32> = (0..mesh.vertex_count() as u32).collect();
    adapt(mesh, &mut grid, &[true], &all, &settings)
}

/// Validates the mesh and returns its components' shapes, asserting they are closed and that
/// nothing crosses anything.
fn closed_and_clean(mesh: &Mesh) -> Vec<ComponentShape> {
    mesh.validate().expect("valid mesh");
    let crossings = find_intersections(mesh);
    assert_eq!(crossings.total(), 0, "{crossings:?}");
    let shapes = mesh.component_shapes();
    assert!(shapes.iter().all(|s| s.is_closed()), "{shapes:?}");
    shapes
}

#[test]
fn two_spheres_within_the_join_distance_become_one() {
    let probe = spheres(8, 0.5, &[Vec3::ZERO]);
    let edge = probe.mean_edge_length();
    let gap = 1.05 * edge;
    let mut mesh = spheres(8, 0.5, &[Vec3::ZERO, Vec3::new(1.0 + gap, 0.0, 0.0)]);
    assert_eq!(closed_and_clean(&mesh).len(), 2);

    let report = fuse_everywhere(&mut mesh);
    assert_eq!((report.joins, report.splits), (1, 0), "{report:?}");
    let shapes = closed_and_clean(&mesh);
    assert_eq!(shapes.len(), 1, "{shapes:?}");
    assert_eq!(shapes[0].genus, 0);
}

#[test]
fn spheres_farther_than_the_join_distance_stay_apart() {
    let probe = spheres(8, 0.5, &[Vec3::ZERO]);
    let gap = 1.5 * probe.mean_edge_length();
    let mut mesh = spheres(8, 0.5, &[Vec3::ZERO, Vec3::new(1.0 + gap, 0.0, 0.0)]);
    let before = mesh.clone();
    let report = fuse_everywhere(&mut mesh);
    assert_eq!((report.contacts, report.joins), (0, 0));
    assert_eq!(mesh.positions(), before.positions());
    assert_eq!(mesh.faces(), before.faces());
}

/// One stroke of `kind` through `points` on layer 0 of `mesh`, fuse when `fuse` holds.
fn stroke(
    pipeline: &mut Pipeline,
    mesh: &mut Mesh,
    (kind, radius, strength): (BrushKind, f32, f32),
    points: &[Vec3],
    fuse: bool,
) -> StrokeReport {
    let mut spec = common::one_brush_stroke(kind, radius, points);
    spec.brush.strength = strength;
    let settings = StrokeSettings {
        fuse: if fuse { vec![0] } else { Vec::new() },
        ..spec.settings()
    };
    pipeline
        .begin_stroke(mesh, settings)
        .expect("stroke begins")
        .finish_with(&spec.samples)
        .expect("stroke runs")
}

#[test]
fn a_grab_pushing_the_north_pole_through_the_south_pole_makes_a_torus() {
    let mut mesh = spheres(16, 1.0, &[Vec3::ZERO]);
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    let push = common::line(Vec3::Y, Vec3::new(0.0, -1.3, 0.0), 24);
    let report = stroke(
        &mut pipeline,
        &mut mesh,
        (BrushKind::Grab, 0.4, 1.0),
        &push,
        true,
    );
    assert!(
        report.clamped > 0,
        "the pole must have reached the far side: {report:?}"
    );
    assert_eq!(report.topology.joins, 1, "{:?}", report.topology);
    let shapes = closed_and_clean(&mesh);
    assert_eq!(shapes.len(), 1, "{shapes:?}");
    assert_eq!(shapes[0].genus, 1, "{shapes:?}");

    // The same stroke on a collide layer: the pole stops at the far side, no genus changes.
    let mut kept = spheres(16, 1.0, &[Vec3::ZERO]);
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    let report = stroke(
        &mut pipeline,
        &mut kept,
        (BrushKind::Grab, 0.4, 1.0),
        &push,
        false,
    );
    assert_eq!(report.topology, TopologyReport::default());
    let shapes = closed_and_clean(&kept);
    assert_eq!((shapes.len(), shapes[0].genus), (1, 0), "{shapes:?}");
}

/// A closed capsule along z: `around` vertices a ring, rings one edge apart, a fan at each end.
/// Its radius follows `radius(z)`; the ring spacing is the circumference over `around` at the
/// ends, so the mesh is near uniform there and the pinched rings are crowded.
fn capsule(around: u32, rings: u32, radius: impl Fn(f32) -> f32) -> Mesh {
    let end_radius = radius(0.0);
    let spacing = std::f32::consts::TAU * end_radius / around as f32;
    let length = spacing * (rings - 1) as f32;
    let mut positions = Vec::new();
    for k in 0..rings {
        let z = k as f32 * spacing;
        let r = radius(z / length);
        for i in 0..around {
            let t = std::f32::consts::TAU * i as f32 / around as f32;
            positions.push(Vec3::new(r * t.cos(), r * t.sin(), z));
        }
    }
    let (bottom, top) = (positions.len() as u32, positions.len() as u32 + 1);
    positions.push(Vec3::new(0.0, 0.0, -0.8 * spacing));
    positions.push(Vec3::new(0.0, 0.0, length + 0.8 * spacing));
    let at = |k: u32, i: u32| k * around + i % around;
    let mut faces = Vec::new();
    for k in 0..rings - 1 {
        for i in 0..around {
            faces.push([at(k, i), at(k, i + 1), at(k + 1, i + 1)]);
            faces.push([at(k, i), at(k + 1, i + 1), at(k + 1, i)]);
        }
    }
    for i in 0..around {
        faces.push([at(0, i + 1), at(0, i), bottom]);
        faces.push([at(rings - 1, i), at(rings - 1, i + 1), top]);
    }
    let layers = vec![0; faces.len()];
    Mesh::new(positions, faces, layers, vec!["blob".into()]).expect("capsule")
}

#[test]
fn a_neck_pinched_below_the_join_distance_splits_into_two_closed_components() {
    // 16 around a ring of radius 1: edges of 0.39. The waist is 0.2 across, under the join
    // distance (1.18 edges = 0.46) and over the collision distance's reach of its own ring.
    let waist = |t: f32| 1.0 - 0.9 * (-((t - 0.5) / 0.08).powi(2)).exp();
    let mut mesh = capsule(16, 24, waist);
    assert_eq!(closed_and_clean(&mesh).len(), 1);

    let report = fuse_everywhere(&mut mesh);
    assert_eq!((report.splits, report.joins), (1, 0), "{report:?}");
    let shapes = closed_and_clean(&mesh);
    assert_eq!(shapes.len(), 2, "{shapes:?}");
    assert!(shapes.iter().all(|s| s.genus == 0), "{shapes:?}");
}

#[test]
fn two_fuse_layers_touching_never_weld() {
    let probe = spheres(8, 0.5, &[Vec3::ZERO]);
    let gap = 1.05 * probe.mean_edge_length();
    let mut mesh = flake_and_plaster(1.0 + gap);
    let edge = mesh.mean_edge_length();
    let settings = FuseSettings::new(&mesh, edge, edge);
    let mut grid = SpatialHash::build(&mesh, edge).expect("grid");
    let all: Vec<u32> = (0..mesh.vertex_count() as u32).collect();
    let report = adapt(&mut mesh, &mut grid, &[true, true], &all, &settings);
    assert_eq!((report.contacts, report.joins, report.splits), (0, 0, 0));
    assert_eq!(closed_and_clean(&mesh).len(), 2);
}

/// 300 seeded strokes of the brushes that move a surface into itself, Freestyle's sweeps
/// among them, over `start` (each from a vertex of the fuse copy, brush radii and reach scaled
/// by `size`), the same on a fuse and on a collide copy: after each, both are closed, valid
/// and free of intersections; the collide copy keeps its genus. Returns the joins and splits
/// made.
fn random_strokes(start: &Mesh, size: f32, seed: u64) -> usize {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let kinds = [
        BrushKind::Grab,
        BrushKind::Draw,
        BrushKind::Inflate,
        BrushKind::Deflate,
        BrushKind::Smooth,
        BrushKind::Pinch,
        BrushKind::Sweep,
        BrushKind::SweepVolume,
    ];
    let genus = start.component_shapes()[0].genus;
    let (mut fused, mut kept) = (start.clone(), start.clone());
    let (mut fuse_pipeline, mut keep_pipeline) = (
        Pipeline::new(PipelineSettings::default()),
        Pipeline::new(PipelineSettings::default()),
    );
    let mut changes = 0;
    let random_vec = |rng: &mut rand_chacha::ChaCha8Rng, r: f32| {
        Vec3::new(
            rng.random_range(-r..r),
            rng.random_range(-r..r),
            rng.random_range(-r..r),
        )
    };
    for i in 0..300 {
        let kind = kinds[rng.random_range(0..kinds.len())];
        let brush = (
            kind,
            rng.random_range(0.16..0.6) * size,
            rng.random_range(0.3..1.0),
        );
        let live: Vec<u32> = (0..fused.vertex_count() as u32)
            .filter(|&v| fused.is_vertex_live(v))
            .collect();
        let start = fused.positions()[live[rng.random_range(0..live.len())] as usize];
        let end = start + random_vec(&mut rng, 0.8 * size);
        let points = common::line(start, end, 6);
        let report = stroke(&mut fuse_pipeline, &mut fused, brush, &points, true);
        changes += report.topology.joins + report.topology.splits;
        closed_and_clean(&fused);
        stroke(&mut keep_pipeline, &mut kept, brush, &points, false);
        let shapes = closed_and_clean(&kept);
        assert_eq!(
            (shapes.len(), shapes[0].genus),
            (1, genus),
            "stroke {i}: {shapes:?}"
        );
    }
    eprintln!(
        "{changes} joins and splits over 300 strokes: {:?}",
        fused.component_shapes()
    );
    changes
}

#[test]
fn random_strokes_keep_a_fuse_sphere_closed_manifold_and_intersection_free() {
    let changes = random_strokes(&spheres(6, 0.5, &[Vec3::ZERO]), 0.5, 27);
    assert!(
        changes > 0,
        "the strokes must have made the surface touch itself"
    );
}

#[test]
fn random_strokes_keep_a_fuse_torus_closed_manifold_and_intersection_free() {
    let ring = common::torus(40, 14, (0.5, 0.2));
    assert_eq!(closed_and_clean(&ring)[0].genus, 1);
    let changes = random_strokes(&ring, 0.6, 28);
    assert!(
        changes > 0,
        "the strokes must have made the surface touch itself"
    );
}

/// Two spheres joined into a dumbbell, its neck deflated stroke after stroke: the collision
/// distance holds the two sides of the neck apart until they are within the join distance
/// all the way round, and then the neck splits into two closed components.
#[test]
fn a_dumbbell_whose_neck_is_deflated_splits_into_two_closed_components() {
    let probe = spheres(12, 0.5, &[Vec3::ZERO]);
    let gap = 1.05 * probe.mean_edge_length();
    let mut mesh = spheres(12, 0.5, &[Vec3::ZERO, Vec3::new(1.0 + gap, 0.0, 0.0)]);
    assert_eq!(fuse_everywhere(&mut mesh).joins, 1);
    assert_eq!(closed_and_clean(&mesh).len(), 1);

    let neck = Vec3::new(0.5 + gap / 2.0, 0.0, 0.0);
    let across = common::line(neck - 0.02 * Vec3::X, neck + 0.02 * Vec3::X, 5);
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    let mut strokes = 0;
    while strokes < 16 {
        strokes += 1;
        let deflate = (BrushKind::Deflate, 0.2, 1.0);
        let report = stroke(&mut pipeline, &mut mesh, deflate, &across, true);
        assert_eq!(report.topology.joins, 0, "{:?}", report.topology);
        closed_and_clean(&mesh);
        if report.topology.splits > 0 {
            break;
        }
    }
    let shapes = closed_and_clean(&mesh);
    assert_eq!(shapes.len(), 2, "after {strokes} strokes: {shapes:?}");
    assert!(shapes.iter().all(|s| s.genus == 0), "{shapes:?}");
    eprintln!("the neck split after {strokes} strokes: {shapes:?}");
}

/// A fuse flake grabbed into a collide plaster: the stroke stops it at the collision distance,
/// and after the stroke nothing joins: layers never weld, whatever their policies.
#[test]
fn a_fuse_flake_pushed_into_a_collide_plaster_never_welds() {
    let mut mesh = flake_and_plaster(1.3);
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    let push = common::line(Vec3::new(0.5, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), 12);
    let report = stroke(
        &mut pipeline,
        &mut mesh,
        (BrushKind::Grab, 0.3, 1.0),
        &push,
        true,
    );
    assert!(
        report.clamped > 0,
        "the flake must reach the plaster: {report:?}"
    );
    assert_eq!((report.topology.joins, report.topology.splits), (0, 0));
    let shapes = closed_and_clean(&mesh);
    assert_eq!(shapes.len(), 2, "{shapes:?}");
    assert_eq!(
        (shapes[0].layer, shapes[1].layer),
        (0, 1),
        "each layer keeps its own component"
    );
}

/// `slayer sculpt` with the fuse policy from the stroke file (`"fuse": ["sphere"]`) or from
/// `--policy`: the grab of docs/topology.md tunnels through the sphere, and `check --json`
/// reports the genus; a layer that does not exist is one line naming the field.
#[test]
fn sculpt_fuses_the_layers_its_stroke_file_or_policy_names() {
    use common::{arg, assert_one_line_error, scratch, slayer, text, write_scene};
    let dir = scratch("fuse-cli");
    let sphere = dir.join("sphere.ply");
    write_scene("sphere", 20_000, &[], &sphere);
    let grab = r#"{"brush": "grab", "radius": 0.15, "strength": 1.0, "layers": [0],
        "samples": [{"position": [-0.2, 0.46, 0]}, {"position": [-0.2, -0.6, 0]}]}"#;
    let genus = |file: &std::path::Path| -> i64 {
        let out = slayer(&["check", arg(file), "--json"]);
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        let shapes = report["component_shapes"]
            .as_array()
            .expect("shapes")
            .clone();
        assert_eq!(shapes.len(), 1, "{shapes:?}");
        assert_eq!(shapes[0]["boundary_loops"], 0);
        shapes[0]["genus"].as_i64().expect("genus")
    };
    let with_fuse = dir.join("with-fuse.json");
    std::fs::write(
        &with_fuse,
        format!(r#"{{"version": 1, "fuse": ["sphere"], "strokes": [{grab}]}}"#),
    )
    .unwrap();
    let plain = dir.join("plain.json");
    std::fs::write(&plain, format!(r#"{{"version": 1, "strokes": [{grab}]}}"#)).unwrap();
    let sculpt = |strokes: &std::path::Path, output: &std::path::Path, extra: &[&str]| {
        let mut args = vec!["sculpt", "--input", arg(&sphere), "--strokes", arg(strokes)];
        args.extend(["--output", arg(output)]);
        args.extend_from_slice(extra);
        slayer(&args)
    };
    let policy_of = |file: &std::path::Path| {
        let out = slayer(&["check", arg(file), "--json"]);
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        report["fuse_layers"].clone()
    };
    for (strokes, extra, expected) in [
        (&with_fuse, &[][..], 1),
        (&plain, &["--policy", "sphere=fuse"][..], 1),
        (&plain, &[][..], 0),
    ] {
        let output = dir.join("out.ply");
        let out = sculpt(strokes, &output, extra);
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert_eq!(genus(&output), expected, "{strokes:?} {extra:?}");
        // The PLY keeps the policy, and `check` reports it.
        let fuses = serde_json::json!(if expected == 1 { vec![0] } else { vec![] });
        assert_eq!(policy_of(&output), fuses, "{strokes:?} {extra:?}");
    }
    // A fuse layer read back from the PLY stays fuse in the next sculpt (a session keeps it
    // too), until `--policy` says otherwise.
    let kept = dir.join("kept.ply");
    let out = sculpt(&plain, &kept, &["--policy", "fuse"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    for (output, extra, fuses) in [
        (dir.join("again.slayer"), &[][..], serde_json::json!([0])),
        (
            dir.join("again.ply"),
            &["--policy", "0=collide"][..],
            serde_json::json!([]),
        ),
    ] {
        let mut args = vec!["sculpt", "--input", arg(&kept), "--strokes", arg(&plain)];
        args.extend(["--output", arg(&output)]);
        args.extend_from_slice(extra);
        let out = slayer(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert_eq!(policy_of(&output), fuses, "{output:?}");
    }
    let wrong = dir.join("wrong.json");
    std::fs::write(
        &wrong,
        format!(r#"{{"version": 1, "fuse": ["blob"], "strokes": [{grab}]}}"#),
    )
    .unwrap();
    assert_one_line_error(
        &sculpt(&wrong, &dir.join("x.ply"), &[]),
        &["fuse[0]", "blob"],
    );
    let out = sculpt(&plain, &dir.join("x.ply"), &["--policy", "sphere=melt"]);
    assert_one_line_error(&out, &["--policy sphere=melt", "collide or fuse"]);
}
