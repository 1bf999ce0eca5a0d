//! Brushes on a lone sheet (nothing to collide with): each moves the way its name says; falloff
//! curves, resampling, and stroke files with every kind of mistake.

use glam::Vec3;
use slayer::brush::{Brush, BrushKind, Falloff, Sample, Stroke, StrokeFile, resample};
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings, Remeshing};
use slayer::scene::shapes;

#[test]
fn falloff_curves_are_one_at_the_centre_zero_at_the_rim_and_decreasing() {
    for falloff in [
        Falloff::blend(3),
        Falloff::blend(6),
        Falloff::Blend { n: 4, inner: 0.5 },
        Falloff::Smooth,
        Falloff::Sphere,
        Falloff::Linear,
    ] {
        assert!((falloff.weight(0.0) - 1.0).abs() < 1e-6, "{falloff:?}");
        assert_eq!(falloff.weight(1.0), 0.0);
        assert_eq!(falloff.weight(1.5), 0.0);
        assert_eq!(falloff.weight(f32::NAN), 0.0);
        let mut last = 1.0;
        for k in 1..=100 {
            let w = falloff.weight(k as f32 / 100.0);
            assert!(
                w <= last + 1e-6 && (0.0..=1.0).contains(&w),
                "{falloff:?} at {k}"
            );
            last = w;
        }
    }
    // Freestyle's blend has zero slope at both ends.
    let b = Falloff::blend(3);
    let h = 1e-3;
    assert!((b.weight(h) - b.weight(0.0)).abs() / h < 1e-2);
    assert!((b.weight(1.0 - h) - b.weight(1.0)).abs() / h < 1e-2);
    // With a plateau (Freestyle's R_i), full strength up to it and the same curve over the
    // rest, still smooth where they meet.
    let core = Falloff::Blend { n: 3, inner: 0.4 };
    for k in 0..=40 {
        assert_eq!(core.weight(k as f32 / 100.0), 1.0);
    }
    assert!((core.weight(0.4 + h) - 1.0).abs() / h < 1e-2);
    assert!((core.weight(0.7) - b.weight(0.5)).abs() < 1e-6);
}

#[test]
fn resampling_spaces_samples_evenly_and_keeps_the_ends() {
    let samples = vec![
        Sample {
            position: Vec3::ZERO,
            pressure: 0.0,
            normal: None,
        },
        Sample {
            position: Vec3::new(10.0, 0.0, 0.0),
            pressure: 1.0,
            normal: None,
        },
        Sample {
            position: Vec3::new(10.0, 5.0, 0.0),
            pressure: 1.0,
            normal: None,
        },
    ];
    let out = resample(&samples, 1.0).unwrap();
    assert_eq!(out.first().unwrap().position, Vec3::ZERO);
    assert_eq!(out.last().unwrap().position, Vec3::new(10.0, 5.0, 0.0));
    assert_eq!(out.len(), 16);
    assert!((out[5].pressure - 0.5).abs() < 1e-6);
    for pair in out.windows(2) {
        // Arc-length steps of 1 (a chord across the corner is shorter).
        assert!(pair[0].position.distance(pair[1].position) <= 1.0 + 1e-5);
    }
    assert_eq!(resample(&samples[..1], 1.0).unwrap().len(), 1);
    assert!(resample(&[], 1.0).unwrap().is_empty());
}

fn sheet() -> Mesh {
    shapes::stacked_sheets(1, 30, 30, 1.0, 0.0)
}

fn stroke(kind: BrushKind, invert: bool, points: &[Vec3]) -> Stroke {
    Stroke {
        paint: None,
        brush: Brush {
            kind,
            radius: 6.0,
            strength: 0.8,
            falloff: Falloff::Smooth,
            invert,
        },
        layers: vec![0],
        spacing: 0.25,
        symmetry: None,
        samples: points
            .iter()
            .map(|&position| Sample {
                position,
                pressure: 1.0,
                normal: Some(Vec3::Z),
            })
            .collect(),
    }
}

/// Applies a stroke without remeshing: these tests follow vertices by index.
fn apply(mesh: &mut Mesh, stroke: &Stroke) {
    Pipeline::new(PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    })
    .apply_stroke(mesh, stroke)
    .unwrap();
    mesh.validate().unwrap();
}

const CENTER: Vec3 = Vec3::new(15.0, 15.0, 0.0);
const CENTER_VERTEX: usize = 15 * 31 + 15;

#[test]
fn draw_raises_and_inverted_draw_lowers() {
    let mut up = sheet();
    apply(&mut up, &stroke(BrushKind::Draw, false, &[CENTER]));
    assert!(up.positions()[CENTER_VERTEX].z > 0.3);
    let mut down = sheet();
    apply(&mut down, &stroke(BrushKind::Draw, true, &[CENTER]));
    assert!(down.positions()[CENTER_VERTEX].z < -0.3);
    // Outside the radius nothing moves.
    assert_eq!(up.positions()[0], sheet().positions()[0]);
}

#[test]
fn inflate_follows_normals_and_deflate_is_its_opposite() {
    let base = slayer::scene::geodesic_sphere(12, 5.0).unwrap();
    let top = (0..base.vertex_count())
        .max_by(|&a, &b| base.positions()[a].z.total_cmp(&base.positions()[b].z))
        .unwrap();
    let at = base.positions()[top];
    for (kind, grows) in [(BrushKind::Inflate, true), (BrushKind::Deflate, false)] {
        let mut mesh = base.clone();
        let mut s = stroke(kind, false, &[at]);
        s.brush.radius = 3.0;
        apply(&mut mesh, &s);
        let r = mesh.positions()[top].length();
        assert!(
            if grows { r > 5.05 } else { r < 4.95 },
            "{kind:?}: radius {r}"
        );
    }
}

#[test]
fn grab_carries_vertices_along_the_stroke() {
    let mut mesh = sheet();
    let lift = Vec3::new(0.5, 0.0, 1.5);
    apply(
        &mut mesh,
        &stroke(BrushKind::Grab, false, &[CENTER, CENTER + lift]),
    );
    let moved = mesh.positions()[CENTER_VERTEX] - sheet().positions()[CENTER_VERTEX];
    assert!((moved - lift).length() < 0.02, "{moved}");
    // Vertices off centre follow by their falloff weight.
    let off = CENTER_VERTEX + 3;
    let weight = Falloff::Smooth.weight(3.0 / 6.0);
    let moved_off = mesh.positions()[off] - sheet().positions()[off];
    assert!((moved_off - lift * weight).length() < 0.02, "{moved_off}");
}

fn height_variance(mesh: &Mesh) -> f32 {
    let zs: Vec<f32> = mesh.positions().iter().map(|p| p.z).collect();
    let mean = zs.iter().sum::<f32>() / zs.len() as f32;
    zs.iter().map(|z| (z - mean) * (z - mean)).sum::<f32>() / zs.len() as f32
}

fn bumpy() -> Mesh {
    let mut mesh = sheet();
    for p in mesh.positions_mut() {
        p.z = 0.3 * ((p.x * 1.7).sin() * (p.y * 2.3).cos());
    }
    mesh.recompute_normals();
    mesh
}

#[test]
fn smooth_and_flatten_reduce_relief() {
    for kind in [BrushKind::Smooth, BrushKind::Flatten] {
        let mut mesh = bumpy();
        let before = height_variance(&mesh);
        let path: Vec<Vec3> = (0..8)
            .map(|k| CENTER + Vec3::new(k as f32 * 0.5 - 2.0, 0.0, 0.0))
            .collect();
        apply(&mut mesh, &stroke(kind, false, &path));
        assert!(height_variance(&mesh) < 0.95 * before, "{kind:?}");
    }
}

#[test]
fn pinch_pulls_in_and_twist_turns_about_the_normal() {
    let probe = CENTER_VERTEX + 2; // two units from the centre along x
    let mut pinched = sheet();
    apply(&mut pinched, &stroke(BrushKind::Pinch, false, &[CENTER]));
    assert!(pinched.positions()[probe].distance(CENTER) < 2.0 - 0.1);
    let mut spread = sheet();
    apply(&mut spread, &stroke(BrushKind::Pinch, true, &[CENTER]));
    assert!(spread.positions()[probe].distance(CENTER) > 2.0 + 0.1);

    let mut twisted = sheet();
    apply(&mut twisted, &stroke(BrushKind::Twist, false, &[CENTER]));
    let p = twisted.positions()[probe];
    assert!(
        (p.distance(CENTER) - 2.0).abs() < 1e-3,
        "a twist keeps distances to the axis"
    );
    assert!(p.y > CENTER.y + 0.2, "counter-clockwise about +z");
    assert!(p.z.abs() < 1e-5);
}

#[test]
fn crease_cuts_a_groove() {
    let mut mesh = sheet();
    apply(&mut mesh, &stroke(BrushKind::Crease, false, &[CENTER]));
    assert!(mesh.positions()[CENTER_VERTEX].z < -0.2);
}

/// What one dab of strength `s`, pressure 1 and falloff weight `w` does to a vertex at `p`
/// (normal `n`, one-ring centroid `ring`), brushed at `center` with radius `r`, brush normal +z
/// and flatten's plane through `plane`: the formulas of `docs/strokes.md`, written here apart
/// from `brush::field`.
fn documented_move(
    kind: BrushKind,
    (s, w, r): (f32, f32, f32),
    p: Vec3,
    n: Vec3,
    ring: Vec3,
    (center, plane): (Vec3, Vec3),
) -> Vec3 {
    let amount = s * w;
    let towards_axis = (center - p) * Vec3::new(1.0, 1.0, 0.0);
    match kind {
        BrushKind::Draw => Vec3::Z * (0.1 * r * amount),
        BrushKind::Inflate => n * (0.1 * r * amount),
        BrushKind::Smooth => (ring - p) * amount.min(1.0),
        BrushKind::Flatten => -Vec3::Z * ((p.z - plane.z) * amount.min(1.0)),
        BrushKind::Trim => -Vec3::Z * ((p.z - plane.z).max(0.0) * amount.min(1.0)),
        BrushKind::Pinch => towards_axis * (0.25 * amount),
        BrushKind::Crease => -Vec3::Z * (0.1 * r * amount) + towards_axis * (0.25 * amount),
        BrushKind::Twist => {
            let turn = glam::Quat::from_rotation_z(0.5 * amount);
            center + turn * (p - center) - p
        }
        _ => unreachable!("{kind:?} is not profiled"),
    }
}

/// Every brush that moves vertices by a formula, one dab at radii of 3, 5 and 8 edges: each
/// vertex moves by the documented amount (not only in the documented direction).
#[test]
fn one_dab_moves_each_vertex_by_the_documented_amount() {
    let kinds = [
        BrushKind::Draw,
        BrushKind::Inflate,
        BrushKind::Smooth,
        BrushKind::Flatten,
        BrushKind::Trim,
        BrushKind::Pinch,
        BrushKind::Crease,
        BrushKind::Twist,
    ];
    for kind in kinds {
        for r in [3.0f32, 5.0, 8.0] {
            let start = if matches!(
                kind,
                BrushKind::Smooth | BrushKind::Flatten | BrushKind::Trim | BrushKind::Inflate
            ) {
                bumpy()
            } else {
                sheet()
            };
            let mut mesh = start.clone();
            let mut s = stroke(kind, false, &[CENTER]);
            s.brush.radius = r;
            apply(&mut mesh, &s);
            let strength = s.brush.strength;
            let weight = |p: Vec3| Falloff::Smooth.weight(p.distance(CENTER) / r);
            // Flatten's and trim's plane: through the weighted centroid of the vertices under the brush.
            let (sum, total) =
                start
                    .positions()
                    .iter()
                    .fold((glam::DVec3::ZERO, 0.0f64), |(a, t), &p| {
                        let w = weight(p) as f64;
                        (a + p.as_dvec3() * w, t + w)
                    });
            let plane = (sum / total).as_vec3();
            let mut worst = 0.0f32;
            let mut moved = 0;
            for v in 0..start.vertex_count() {
                let p = start.positions()[v];
                let ring = start.neighbours(v as u32);
                let centroid = ring
                    .iter()
                    .map(|&u| start.positions()[u as usize])
                    .sum::<Vec3>()
                    / ring.len() as f32;
                let expected = documented_move(
                    kind,
                    (strength, weight(p), r),
                    p,
                    start.normals()[v],
                    centroid,
                    (CENTER, plane),
                );
                let actual = mesh.positions()[v] - p;
                worst = worst.max((actual - expected).length());
                moved += usize::from(actual.length() > 1e-4);
            }
            assert!(moved > 10, "{kind:?} at radius {r}: {moved} vertices moved");
            assert!(
                worst <= 1e-4 * r,
                "{kind:?} at radius {r}: {worst:e} off the formula"
            );
        }
    }
}

fn parse(text: &str) -> Result<Vec<Stroke>, String> {
    let mesh = shapes::stacked_sheets(2, 4, 4, 1.0, 2.0);
    StrokeFile::parse(text, "s.json")
        .and_then(|f| f.resolve(&mesh, "s.json"))
        .map_err(|e| e.to_string())
}

fn one(stroke_fields: &str) -> String {
    format!(r#"{{"strokes": [{{{stroke_fields}}}]}}"#)
}

#[test]
fn stroke_files_resolve_names_and_defaults() {
    let strokes = parse(&one(r#""brush": "move", "radius": 1.5, "strength": 0.5, "layers": ["layer1", 0],
        "samples": [{"position": [1, 1, 2]}, {"position": [2, 1, 2], "pressure": 0.5, "normal": [0, 0, 2]}]"#))
    .unwrap();
    let s = &strokes[0];
    assert_eq!(s.brush.kind, BrushKind::Grab);
    assert_eq!(s.layers, vec![0, 1]);
    assert_eq!(s.spacing, 0.25);
    assert_eq!(s.brush.falloff, Falloff::blend(3));
    assert_eq!(s.samples[0].pressure, 1.0);
    assert_eq!(s.samples[1].normal, Some(Vec3::Z));
    let swept = parse(&one(
        r#""brush": "sweep-volume", "radius": 1.5, "strength": 0.5, "layers": [0],
        "falloff": {"curve": "blend", "n": 4, "inner": 0.5}, "samples": [{"position": [1, 1, 2]}]"#,
    ))
    .unwrap();
    assert_eq!(swept[0].brush.kind, BrushKind::SweepVolume);
    assert_eq!(swept[0].brush.falloff, Falloff::Blend { n: 4, inner: 0.5 });
}

#[test]
fn bad_stroke_files_name_the_problem_and_where() {
    let ok_sample = r#""samples": [{"position": [1, 1, 2]}]"#;
    let cases = [
        (
            one(&format!(
                r#""brush": "smudge", "radius": 1, "strength": 0.5, "layers": [0], {ok_sample}"#
            )),
            "strokes[0].brush: the text \"smudge\" is not a brush (brushes: draw,",
        ),
        (
            one(&format!(
                r#""brush": "draw", "radius": -1, "strength": 0.5, "layers": [0], {ok_sample}"#
            )),
            "strokes[0].radius: -1 is not a positive length",
        ),
        (
            one(&format!(
                r#""brush": "draw", "radius": 1e9, "strength": 0.5, "layers": [0], {ok_sample}"#
            )),
            "times the mesh's size",
        ),
        (
            one(&format!(
                r#""brush": "draw", "strength": 0.5, "layers": [0], {ok_sample}"#
            )),
            "strokes[0].radius: missing",
        ),
        (
            one(&format!(
                r#""brush": "draw", "radius": 1, "strength": 3, "layers": [0], {ok_sample}"#
            )),
            "strokes[0].strength: 3 is outside [0, 1]",
        ),
        (
            one(&format!(
                r#""brush": "draw", "radius": 1, "strength": 0.5, "layers": [7], {ok_sample}"#
            )),
            "strokes[0].layers[0]: layer 7 does not exist",
        ),
        (
            one(&format!(
                r#""brush": "draw", "radius": 1, "strength": 0.5, "layers": ["paint"], {ok_sample}"#
            )),
            "no layer is named `paint`",
        ),
        (
            one(r#""brush": "draw", "radius": 1, "strength": 0.5, "layers": [0], "samples": []"#),
            "at least one sample",
        ),
        (
            one(
                r#""brush": "draw", "radius": 1, "strength": 0.5, "layers": [0], "samples": [{"position": [1, NaN, 2]}]"#,
            ),
            "s.json:1:",
        ),
        (
            one(
                r#""brush": "draw", "radius": 1, "strength": 0.5, "layers": [0], "samples": [{"position": [1, 1e39, 2]}]"#,
            ),
            "strokes[0].samples[0].position",
        ),
        (
            one(
                r#""brush": "draw", "radius": 1, "strength": 0.5, "layers": [0], "samples": [{"position": [1, 1, 2], "pressure": 2}]"#,
            ),
            "samples[0].pressure: 2 is outside [0, 1]",
        ),
        (
            one(
                r#""brush": "draw", "radius": 1, "strength": 0.5, "layers": [0], "samples": [{"position": [1, 1, 2], "normal": [0, 0, 0]}]"#,
            ),
            "is not a direction",
        ),
        (
            one(&format!(
                r#""brush": "draw", "radius": 1, "strength": 0.5, "layers": [0], "falloff": {{"curve": "blend", "n": 2}}, {ok_sample}"#
            )),
            "the blend needs n > 2",
        ),
        (
            one(&format!(
                r#""brush": "sweep", "radius": 1, "strength": 0.5, "layers": [0], "falloff": {{"curve": "blend", "inner": 1.5}}, {ok_sample}"#
            )),
            "strokes[0].falloff.inner: 1.5 is outside [0, 0.95]",
        ),
        (
            one(&format!(
                r#""brush": "sweep", "radius": 1, "strength": 0.5, "layers": [0], "falloff": {{"curve": "smooth", "inner": 0.5}}, {ok_sample}"#
            )),
            "only the blend curve takes an `inner`",
        ),
        (
            one(&format!(
                r#""brush": "draw", "radius": 1, "strength": 0.5, "layers": [0], "colour": 3, {ok_sample}"#
            )),
            "unknown field `colour`",
        ),
        ("{\"strokes\": [".to_string(), "s.json:1:"),
        (
            r#"{"version": 2, "strokes": []}"#.to_string(),
            "version 2 is not supported",
        ),
    ];
    for (text, expected) in cases {
        let e = parse(&text).unwrap_err();
        assert!(
            e.contains(expected),
            "{text}\n  got: {e}\n  expected: {expected}"
        );
        assert!(!e.contains('\n'));
    }
}

/// The longest move a dab's settings allow (`move_bound`, which decides where a GPU run records
/// a sample's two steps ahead) bounds every brush's displacement of any vertex within its
/// radius, at any weight, pressure, share, normal and flatten plane point under the brush.
#[test]
fn no_brush_moves_a_vertex_farther_than_its_settings_allow() {
    use proptest::prelude::*;
    use slayer::brush::{Dab, DabFrame, displacement, move_bound};
    let unit = || (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0);
    let settings = (
        0usize..BrushKind::ALL.len(),
        0.01f32..5.0,
        0.0f32..=1.0,
        any::<bool>(),
    );
    let dab = (0.0f32..=1.0, 0.0f32..=1.0, unit(), unit(), unit(), unit());
    let at = (unit(), unit(), 0.0f32..=1.0);
    proptest!(|((kind, radius, strength, invert) in settings,
                 (pressure, share, normal, plane, motion, center) in dab,
                 (offset, ring, weight) in at)| {
        let v = |(x, y, z): (f32, f32, f32)| Vec3::new(x, y, z);
        let normal = v(normal).try_normalize().unwrap_or(Vec3::Z);
        let center = v(center) * 3.0;
        // Within the radius: the vertex and the flatten's plane point (a centroid under it).
        let inside = |p: Vec3| center + p.clamp_length_max(1.0) * radius;
        let brush = Brush {
            kind: BrushKind::ALL[kind],
            radius,
            strength,
            falloff: Falloff::Smooth,
            invert,
        };
        let dab = Dab {
            brush,
            frame: DabFrame { center, normal, plane_point: inside(v(plane)), motion: v(motion) },
            pressure,
            share: share.max(1e-3),
        };
        let position = inside(v(offset));
        let moved = displacement(&dab, position, normal, position + v(ring), weight).length();
        match move_bound(&dab) {
            Some(bound) => prop_assert!(moved <= bound * (1.0 + 1e-5) + 1e-6,
                "{:?}: {moved} > {bound}", brush.kind),
            None => prop_assert_eq!(brush.kind, BrushKind::Smooth),
        }
    });
}
