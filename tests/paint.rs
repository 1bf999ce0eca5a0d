//! Reflectance painting: the linear BRDF blend, the paint brush alone and riding along with a
//! deformation, stencils (generated and PNG) projected along the brush normal, paint in stroke
//! files, and remeshing carrying BRDFs along.

use std::sync::Arc;

use glam::Vec3;
use proptest::prelude::*;
use slayer::brush::{
    Brush, BrushKind, Falloff, Paint, Pattern, Sample, Stencil, Stroke, StrokeFile,
};
use slayer::material;
use slayer::mesh::{Brdf, Mesh, VertexFlags};
use slayer::pipeline::{Pipeline, PipelineSettings};
use slayer::render::brdf::blinn_exponent;
use slayer::scene::shapes;

fn brdf_strategy() -> impl Strategy<Value = Brdf> {
    prop::array::uniform7(0.0f32..=1.0).prop_map(Brdf::from_array)
}

fn close(a: &Brdf, b: &Brdf, tolerance: f32) -> bool {
    a.as_array()
        .iter()
        .zip(b.as_array())
        .all(|(x, y)| (x - y).abs() <= tolerance)
}

proptest! {
    #[test]
    fn blending_stays_between_its_inputs(a in brdf_strategy(), b in brdf_strategy(), t in 0.0f32..=1.0) {
        let mixed = a.lerp(&b, t);
        prop_assert!(mixed.in_range());
        for ((m, x), y) in mixed.as_array().iter().zip(a.as_array()).zip(b.as_array()) {
            prop_assert!(*m >= x.min(y) - 1e-6 && *m <= x.max(y) + 1e-6);
        }
    }

    #[test]
    fn blending_is_linear(a in brdf_strategy(), b in brdf_strategy(), s in 0.0f32..=1.0, t in 0.0f32..=1.0, u in 0.0f32..=1.0) {
        prop_assert_eq!(a.lerp(&b, 0.0), a);
        prop_assert!(close(&a.lerp(&b, 1.0), &b, 1e-6));
        // Mixing two mixes of a and b is a mix of a and b, at the mixed weight.
        let nested = a.lerp(&b, s).lerp(&a.lerp(&b, t), u);
        prop_assert!(close(&nested, &a.lerp(&b, s + (t - s) * u), 1e-5));
        // Blending commutes with swapping the ends.
        prop_assert!(close(&a.lerp(&b, t), &b.lerp(&a, 1.0 - t), 1e-6));
    }
}

#[test]
fn roughness_maps_to_a_finite_decreasing_blinn_exponent() {
    assert_eq!(blinn_exponent(1.0), 0.0);
    let sharpest = blinn_exponent(0.0);
    assert!(sharpest.is_finite() && sharpest > 1000.0, "{sharpest}");
    let mut last = f32::INFINITY;
    for k in 0..=100 {
        let e = blinn_exponent(k as f32 / 100.0);
        assert!(e.is_finite() && e >= 0.0 && e <= last, "r = {k}%: {e}");
        last = e;
    }
    // Out-of-range and NaN roughness stay usable.
    assert_eq!(blinn_exponent(2.0), 0.0);
    assert_eq!(blinn_exponent(-1.0), sharpest);
    assert_eq!(blinn_exponent(f32::NAN), 0.0);
}

#[test]
fn presets_are_in_range_and_distinct() {
    for (i, m) in material::PRESETS.iter().enumerate() {
        assert!(m.brdf.in_range(), "{}", m.name);
        for other in &material::PRESETS[..i] {
            assert_ne!(m.brdf, other.brdf, "{} and {}", m.name, other.name);
        }
    }
}

const RADIUS: f32 = 5.0;
const CENTER: Vec3 = Vec3::new(10.0, 10.0, 0.0);

/// Two stacked 20 × 20 sheets, 0.5 apart; every vertex in clay.
fn two_sheets() -> Mesh {
    shapes::stacked_sheets(2, 20, 20, 1.0, 0.5)
}

fn stroke(kind: BrushKind, paint: Option<Paint>, layers: Vec<u32>, at: Vec3) -> Stroke {
    Stroke {
        brush: Brush {
            kind,
            radius: RADIUS,
            strength: 1.0,
            falloff: Falloff::Smooth,
            invert: false,
        },
        paint,
        layers,
        spacing: 0.25,
        symmetry: None,
        samples: vec![Sample {
            position: at,
            pressure: 1.0,
            normal: Some(Vec3::Z),
        }],
    }
}

fn apply(mesh: &mut Mesh, stroke: &Stroke) {
    let mut reference = mesh.clone();
    Pipeline::new(PipelineSettings::default())
        .apply_stroke(mesh, stroke)
        .unwrap();
    mesh.validate().unwrap();
    Pipeline::reference(PipelineSettings::default())
        .apply_stroke(&mut reference, stroke)
        .unwrap();
    // Both backends paint and move the same bits.
    assert_eq!(reference.brdfs(), mesh.brdfs(), "backends disagree");
    assert_eq!(reference.positions(), mesh.positions(), "backends disagree");
}

#[test]
fn paint_brush_blends_by_falloff_weight_on_active_unmasked_vertices_only() {
    let rust = material::RUST.brdf;
    let mut mesh = two_sheets();
    let before = mesh.clone();
    // Mask one vertex near the centre of the top sheet.
    let masked = (0..mesh.vertex_count())
        .find(|&v| {
            mesh.vertex_layers()[v] == 1
                && mesh.positions()[v].truncate() == CENTER.truncate() + glam::Vec2::X
        })
        .unwrap();
    mesh.flags_mut()[masked].insert(VertexFlags::MASKED);
    let at = CENTER + Vec3::Z * 0.5;
    let s = stroke(BrushKind::Paint, Some(Paint::material(rust)), vec![1], at);
    apply(&mut mesh, &s);

    assert_eq!(mesh.positions(), before.positions(), "paint moved vertices");
    let mut painted = 0;
    for v in 0..mesh.vertex_count() {
        let p = mesh.positions()[v];
        let weight = Falloff::Smooth.weight(p.distance(at) / RADIUS);
        let expected = if mesh.vertex_layers()[v] == 1 && v != masked && weight > 0.0 {
            painted += 1;
            Brdf::CLAY.lerp(&rust, weight)
        } else {
            Brdf::CLAY
        };
        assert!(
            close(&mesh.brdfs()[v], &expected, 1e-6),
            "vertex {v} at {p}: {:?}, expected {expected:?}",
            mesh.brdfs()[v]
        );
        assert!(mesh.brdfs()[v].in_range());
    }
    assert!(painted > 40, "{painted} vertices painted");
}

#[test]
fn paint_brush_strength_and_pressure_scale_the_blend() {
    let rust = material::RUST.brdf;
    let mut mesh = two_sheets();
    let at = CENTER + Vec3::Z * 0.5;
    // Through a stroke file, so `strength` folds into the opacity as documented.
    let mut file = StrokeFile::parse(
        r#"{"strokes": [{"brush": "paint", "radius": 5, "strength": 0.5, "falloff": {"curve": "smooth"},
            "layers": [1], "paint": {"material": "rust"},
            "samples": [{"position": [10, 10, 0.5], "pressure": 0.5, "normal": [0, 0, 1]}]}]}"#,
        "inline",
    )
    .unwrap()
    .resolve(&mesh, "inline")
    .unwrap();
    let from_file = file.remove(0);
    assert_eq!(from_file.paint.as_ref().unwrap().opacity, 0.5);
    apply(&mut mesh, &from_file);
    let centre = (0..mesh.vertex_count())
        .find(|&v| mesh.positions()[v] == at)
        .unwrap();
    // Weight 1 at the centre × pressure 0.5 × strength 0.5.
    assert!(close(
        &mesh.brdfs()[centre],
        &Brdf::CLAY.lerp(&rust, 0.25),
        1e-6
    ));
}

#[test]
fn a_deforming_brush_paints_in_the_same_pass() {
    let paint = material::PAINT.brdf;
    let mut mesh = two_sheets();
    let before = mesh.clone();
    let at = CENTER + Vec3::Z * 0.5;
    let s = stroke(BrushKind::Draw, Some(Paint::material(paint)), vec![1], at);
    apply(&mut mesh, &s);
    let mut moved_and_painted = 0;
    for v in 0..mesh.vertex_count() {
        let moved = mesh.positions()[v] != before.positions()[v];
        let painted = mesh.brdfs()[v] != Brdf::CLAY;
        // Painted at the weight of where the vertex was when the brush arrived.
        let weight = Falloff::Smooth.weight(before.positions()[v].distance(at) / RADIUS);
        if painted {
            assert_eq!(mesh.vertex_layers()[v], 1);
            assert!(close(
                &mesh.brdfs()[v],
                &Brdf::CLAY.lerp(&paint, weight),
                1e-6
            ));
        }
        if moved {
            assert!(painted, "vertex {v} moved but was not painted");
            moved_and_painted += 1;
        }
    }
    assert!(moved_and_painted > 40);
    // Without paint, the same stroke moves the same way and paints nothing.
    let mut plain = before.clone();
    apply(
        &mut plain,
        &stroke(BrushKind::Draw, None, vec![1], CENTER + Vec3::Z * 0.5),
    );
    assert_eq!(plain.positions(), mesh.positions());
    assert!(plain.brdfs().iter().all(|b| *b == Brdf::CLAY));
}

#[test]
fn stencils_are_projected_along_the_brush_normal_and_tile() {
    let (a, b) = (material::PLASTER.brdf, material::RUST.brdf);
    let stencil = Stencil::pattern(Pattern::Checker, a, b, 2.0);
    // +z: u along x, v along y, one repeat every 2 units; quadrant centres are pure texels.
    assert_eq!(stencil.at(Vec3::new(0.5, 0.5, 0.0), Vec3::Z), a);
    assert_eq!(stencil.at(Vec3::new(1.5, 0.5, 0.0), Vec3::Z), b);
    assert_eq!(stencil.at(Vec3::new(0.5, 1.5, 0.0), Vec3::Z), b);
    assert_eq!(stencil.at(Vec3::new(1.5, 1.5, 0.0), Vec3::Z), a);
    assert_eq!(stencil.at(Vec3::new(4.5, -1.5, 0.0), Vec3::Z), a, "tiles");
    // Moving along the normal does not change what is painted, for any normal.
    for normal in [Vec3::Z, Vec3::new(0.3, -0.5, 0.8).normalize(), -Vec3::X] {
        for p in [Vec3::new(0.3, 1.7, 0.2), Vec3::new(-5.0, 2.0, 9.0)] {
            let here = stencil.at(p, normal);
            let along = stencil.at(p + normal * 3.7, normal);
            assert!(close(&here, &along, 1e-4), "{normal} {p}");
        }
    }
    // Between texels the stencil is a linear mix: on the edge between a and b, half of each.
    let edge = stencil.sample(0.5, 0.25);
    assert!(close(&edge, &a.lerp(&b, 0.5), 1e-5), "{edge:?}");
}

#[test]
fn a_stencil_stroke_paints_the_stencil_at_each_vertex() {
    let (a, b) = (material::PAINT.brdf, material::BARE_METAL.brdf);
    let stencil = Arc::new(Stencil::pattern(Pattern::Stripes, a, b, 3.0));
    let paint = Paint {
        brdf: a,
        stencil: Some(stencil.clone()),
        opacity: 1.0,
    };
    let mut mesh = two_sheets();
    let at = CENTER + Vec3::Z * 0.5;
    apply(
        &mut mesh,
        &stroke(BrushKind::Paint, Some(paint), vec![1], at),
    );
    let mut seen = [false, false];
    for v in 0..mesh.vertex_count() {
        let p = mesh.positions()[v];
        let weight = Falloff::Smooth.weight(p.distance(at) / RADIUS);
        if mesh.vertex_layers()[v] != 1 || weight == 0.0 {
            continue;
        }
        let texel = stencil.at(p, Vec3::Z);
        assert!(close(
            &mesh.brdfs()[v],
            &Brdf::CLAY.lerp(&texel, weight),
            1e-6
        ));
        seen[0] |= texel == a;
        seen[1] |= texel == b;
    }
    assert!(seen[0] && seen[1], "both stripes painted");
}

#[test]
fn png_stencils_carry_diffuse_in_rgb_and_roughness_in_alpha() {
    // 2 × 1 pixels: opaque red, then half-transparent grey.
    let pixels = [255u8, 0, 0, 255, 128, 128, 128, 64];
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &pixels,
        2,
        1,
        image::ExtendedColorType::Rgba8,
    )
    .unwrap();
    let stencil = Stencil::from_png(&png, [0.05; 3], 1.0).unwrap();
    assert_eq!(stencil.size(), (2, 1));
    let red = stencil.sample(0.25, 0.5);
    assert_eq!(red, Brdf::new([1.0, 0.0, 0.0], [0.05; 3], 1.0));
    let grey = stencil.sample(0.75, 0.5);
    // sRGB 128 is linear 0.2158.
    assert!((grey.diffuse[0] - 0.2158).abs() < 1e-3, "{grey:?}");
    assert!((grey.roughness - 64.0 / 255.0).abs() < 1e-6);
    assert!(Stencil::from_png(b"not a png", [0.0; 3], 1.0).is_err());
}

fn stroke_error(paint_json: &str, brush: &str) -> String {
    let text = format!(
        r#"{{"strokes": [{{"brush": "{brush}", "radius": 5, "strength": 0.5, "layers": [1],
            {paint_json} "samples": [{{"position": [10, 10, 0.5]}}]}}]}}"#
    );
    match StrokeFile::parse(&text, "s.json").and_then(|f| f.resolve(&two_sheets(), "s.json")) {
        Ok(_) => panic!("accepted: {paint_json}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn paint_mistakes_in_stroke_files_name_the_field() {
    let cases = [
        ("", "paint", "strokes[0].paint: the paint brush needs"),
        (
            r#""paint": {"material": "gold"},"#,
            "draw",
            "strokes[0].paint.material: no material named `gold`",
        ),
        (
            r#""paint": {"diffuse": [0.5, 0.5, 0.5]},"#,
            "draw",
            "strokes[0].paint.specular: missing",
        ),
        (
            r#""paint": {"material": "rust", "diffuse": [0.5, 1.5, 0.5]},"#,
            "draw",
            "strokes[0].paint.diffuse: 1.5 is outside [0, 1]",
        ),
        (
            r#""paint": {"material": "rust", "opacity": -1},"#,
            "paint",
            "strokes[0].paint.opacity",
        ),
        (
            r#""paint": {"material": "rust", "stencil": {"pattern": "plaid", "tile": 1}},"#,
            "paint",
            "strokes[0].paint.stencil.pattern: no pattern named `plaid`",
        ),
        (
            r#""paint": {"material": "rust", "stencil": {"pattern": "spots", "tile": 0}},"#,
            "paint",
            "strokes[0].paint.stencil.tile",
        ),
        (
            r#""paint": {"material": "rust", "stencil": {"png": "/no/such.png", "tile": 1}},"#,
            "paint",
            "strokes[0].paint.stencil.png: cannot read `/no/such.png`",
        ),
        (
            r#""paint": {"material": "rust", "stencil": {"tile": 1}},"#,
            "paint",
            "strokes[0].paint.stencil: give a `pattern` or a `png`",
        ),
    ];
    for (paint, brush, expected) in cases {
        let message = stroke_error(paint, brush);
        assert!(message.contains(expected), "{paint}: {message}");
    }
    // Unknown fields are caught by the parser, with the line.
    let message = stroke_error(r#""paint": {"colour": [1, 0, 0]},"#, "draw");
    assert!(message.contains("unknown field `colour`"), "{message}");
}

#[test]
fn a_paint_spec_round_trips_through_json() {
    let text = r#"{"version": 1, "strokes": [{"brush": "paint", "radius": 5.0, "strength": 1.0,
        "layers": [1], "paint": {"material": "rust", "roughness": 0.3,
        "stencil": {"pattern": "spots", "with": "bare-metal", "tile": 0.5}},
        "samples": [{"position": [10.0, 10.0, 0.5]}]}]}"#;
    let file = StrokeFile::parse(text, "s.json").unwrap();
    let again = StrokeFile::parse(&file.to_json(), "again").unwrap();
    assert_eq!(file, again);
    let stroke = &again.resolve(&two_sheets(), "again").unwrap()[0];
    let paint = stroke.paint.as_ref().unwrap();
    assert_eq!(paint.brdf.roughness, 0.3);
    assert!(paint.stencil.is_some());
}

#[test]
fn splitting_an_edge_interpolates_the_brdf() {
    let mut mesh = shapes::stacked_sheets(1, 3, 3, 1.0, 0.0);
    let brdfs: Vec<Brdf> = (0..mesh.vertex_count())
        .map(|v| {
            let t = v as f32 / mesh.vertex_count() as f32;
            material::PLASTER.brdf.lerp(&material::RUST.brdf, t)
        })
        .collect();
    mesh.set_brdfs(brdfs).unwrap();
    let corner = 0;
    let (a, b) = mesh.edge_vertices(corner);
    let (ba, bb) = (mesh.brdfs()[a as usize], mesh.brdfs()[b as usize]);
    let m = mesh.split_edge(corner, 0.25);
    mesh.validate().unwrap();
    // `t` runs from the edge's first vertex, as the position does.
    let pa = mesh.positions()[a as usize];
    let t = mesh.positions()[m as usize].distance(pa) / mesh.positions()[b as usize].distance(pa);
    assert!(close(&mesh.brdfs()[m as usize], &ba.lerp(&bb, t), 1e-6));
    assert!(mesh.brdfs()[m as usize].in_range());
}
