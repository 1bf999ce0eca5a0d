//! Freestyle's brushes: sweep carries what is under the brush along the brush's motion (the
//! blend's plateau at full strength), sweep-volume does so while each closed layer keeps its
//! volume, and trim cuts down only what stands above its plane, where flatten also lifts what
//! lies below it.

mod common;

use glam::Vec3;
use slayer::brush::{BrushKind, Falloff, Stroke};
use slayer::collide::find_intersections;
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings, Remeshing, StrokeReport};
use slayer::scene::geodesic_sphere;

/// A stroke of `kind` on layer 0 along `points`, with a blend falloff of plateau `inner`.
fn swept(kind: BrushKind, radius: f32, inner: f32, points: &[Vec3]) -> Stroke {
    let mut stroke = common::one_brush_stroke(kind, radius, points);
    stroke.brush.falloff = Falloff::Blend { n: 3, inner };
    stroke
}

fn apply(mesh: &mut Mesh, stroke: &Stroke) -> StrokeReport {
    let report = Pipeline::new(PipelineSettings::default())
        .apply_stroke(mesh, stroke)
        .expect("stroke runs");
    mesh.validate().expect("valid mesh");
    assert_eq!(find_intersections(mesh).total(), 0);
    report
}

fn highest(mesh: &Mesh) -> f32 {
    (0..mesh.vertex_count() as u32)
        .filter(|&v| mesh.is_vertex_live(v))
        .map(|v| mesh.positions()[v as usize].z)
        .fold(f32::MIN, f32::max)
}

/// From the north pole of a unit sphere straight up by `lift`.
fn pull_up(lift: f32) -> Vec<Vec3> {
    common::line(Vec3::Z, Vec3::new(0.0, 0.0, 1.0 + lift), 16)
}

#[test]
fn sweep_draws_the_surface_out_with_the_brush() {
    let mut mesh = geodesic_sphere(24, 1.0).expect("sphere");
    let report = apply(
        &mut mesh,
        &swept(BrushKind::Sweep, 0.35, 0.5, &pull_up(0.8)),
    );
    // The plateau moves with the brush: the pole ends where the brush does.
    let top = highest(&mesh);
    assert!((top - 1.8).abs() < 0.05, "the tip is at {top}: {report:?}");
    assert!(
        report.remesh.splits > 0,
        "the drawn-out surface is remeshed"
    );
    // Unlike a grab, a sweep selects anew at each sample: a sweep that turns back along the
    // surface leaves its first catch behind.
    let mut there_and_back = geodesic_sphere(24, 1.0).expect("sphere");
    let path: Vec<Vec3> = common::line(Vec3::Z, Vec3::new(0.0, 0.0, 1.4), 8)
        .into_iter()
        .chain(common::line(
            Vec3::new(0.0, 0.0, 1.4),
            Vec3::new(0.6, 0.0, 1.4),
            8,
        ))
        .collect();
    apply(
        &mut there_and_back,
        &swept(BrushKind::Sweep, 0.35, 0.5, &path),
    );
    assert!(highest(&there_and_back) > 1.3);
}

#[test]
fn sweep_volume_keeps_a_closed_layer_within_one_percent_over_a_stroke() {
    let start = geodesic_sphere(24, 1.0).expect("sphere");
    let before = common::closed_volume(&start);
    let mut plain = start.clone();
    apply(
        &mut plain,
        &swept(BrushKind::Sweep, 0.35, 0.5, &pull_up(0.8)),
    );
    let grown = common::closed_volume(&plain) / before - 1.0;
    assert!(grown > 0.02, "a plain sweep adds volume: {grown:+.4}");

    for path in [
        pull_up(0.8),
        // Along the surface and off it at once.
        common::line(Vec3::Z, Vec3::new(0.7, 0.2, 1.3), 16),
        // Pressed in.
        common::line(Vec3::Z, Vec3::new(0.0, 0.0, 0.5), 12),
    ] {
        let mut kept = start.clone();
        let report = apply(&mut kept, &swept(BrushKind::SweepVolume, 0.35, 0.5, &path));
        let change = common::closed_volume(&kept) / before - 1.0;
        assert!(
            change.abs() < 0.01,
            "volume changed {change:+.4}: {report:?}"
        );
        let moved = (0..kept.vertex_count().min(start.vertex_count()))
            .filter(|&v| kept.positions()[v].distance(start.positions()[v]) > 0.05)
            .count();
        assert!(moved > 20, "only {moved} vertices moved");
    }
    // Still drawn out: the tip follows the brush, the flanks give the volume back.
    let mut kept = start.clone();
    apply(
        &mut kept,
        &swept(BrushKind::SweepVolume, 0.35, 0.5, &pull_up(0.8)),
    );
    assert!(highest(&kept) > 1.6, "tip at {}", highest(&kept));
}

/// A sheet with ridges, so that the plane under the brush has material on both sides.
fn ridged_sheet() -> Mesh {
    let mut mesh = slayer::scene::shapes::stacked_sheets(1, 30, 30, 1.0, 0.0);
    for p in mesh.positions_mut() {
        p.z = 0.4 * (p.x * 1.3).sin() * (p.y * 0.9).cos();
    }
    mesh.recompute_normals();
    mesh
}

#[test]
fn trim_cuts_what_stands_above_its_plane_and_leaves_what_lies_below() {
    let start = ridged_sheet();
    let at = Vec3::new(15.0, 15.0, 0.0);
    let run = |kind: BrushKind, invert: bool| {
        let mut mesh = start.clone();
        let mut stroke = common::one_brush_stroke(kind, 6.0, &[at]);
        stroke.brush.invert = invert;
        stroke.samples[0].normal = Some(Vec3::Z);
        Pipeline::new(PipelineSettings {
            remeshing: Remeshing::Off,
            ..PipelineSettings::default()
        })
        .apply_stroke(&mut mesh, &stroke)
        .expect("stroke runs");
        mesh.validate().expect("valid");
        let rises: Vec<f32> = (mesh.positions().iter().zip(start.positions()))
            .map(|(q, p)| q.z - p.z)
            .collect();
        let most = |f: fn(f32, f32) -> f32| rises.iter().copied().fold(0.0, f);
        (most(f32::max), most(f32::min))
    };
    let (up, down) = run(BrushKind::Trim, false);
    assert!(down < -0.05 && up == 0.0, "trim: up {up}, down {down}");
    let (up, down) = run(BrushKind::Trim, true);
    assert!(up > 0.05 && down == 0.0, "fill: up {up}, down {down}");
    let (up, down) = run(BrushKind::Flatten, false);
    assert!(up > 0.05 && down < -0.05, "flatten: up {up}, down {down}");
}
