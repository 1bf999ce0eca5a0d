//! Culling changes nothing: the collision searches skipped where a layer is a sheet that cannot
//! touch itself (`collide::sheet`), or where no other layer is near, would have found nothing.
//! Every stroke here runs twice, culled and not, on shapes chosen to break a careless bound —
//! a sheet folded back onto itself, a crumpled one, pinched, twisted and creased ones, a closed
//! sphere and a layered material with remeshing on — and must end bit-identical, with the same
//! clamps and undos. The flat sheet shows the culling acts at all, the steep ridge that it
//! acts where a sheet's bound on proximity fails, vertex by vertex, and the narrow groove
//! that a vertex's own bound still lets its sheet's other wall be found.

mod common;

use common::reshaped;
use glam::Vec3;
use slayer::bench::{BrushMix, ScriptSpec, generate_script};
use slayer::brush::{Brush, BrushKind, Falloff, Sample, Stroke};
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings, Remeshing};
use slayer::scene::{SceneKind, SceneSpec, generate};

fn scene(kind: SceneKind, triangles: usize) -> Mesh {
    generate(&SceneSpec {
        kind,
        triangles,
        seed: 3,
    })
    .unwrap()
}

fn script(mesh: &Mesh, mix: BrushMix, strokes: usize) -> Vec<Stroke> {
    let spec = ScriptSpec {
        strokes,
        seed: 5,
        samples: 12,
        mix,
        ..ScriptSpec::default()
    };
    generate_script(mesh, &spec)
        .resolve(mesh, "script")
        .unwrap()
}

/// What one run did: the mesh's digest, and its clamps, undos and culled steps.
#[derive(Debug)]
struct Run {
    digest: String,
    clamped: usize,
    reverted: usize,
    culled_steps: usize,
    culled_vertices: usize,
    steps: usize,
    /// Remeshing edits a sheet zone vouched for.
    remesh_culled: usize,
}

fn run(mesh: &Mesh, strokes: &[Stroke], remeshing: Remeshing, cull: bool) -> Run {
    let mut mesh = mesh.clone();
    let mut pipeline = Pipeline::new(PipelineSettings {
        remeshing,
        cull,
        ..PipelineSettings::default()
    });
    let mut outcome = Run {
        digest: String::new(),
        clamped: 0,
        reverted: 0,
        culled_steps: 0,
        culled_vertices: 0,
        steps: 0,
        remesh_culled: 0,
    };
    for stroke in strokes {
        let report = pipeline.apply_stroke(&mut mesh, stroke).unwrap();
        outcome.clamped += report.clamped;
        outcome.reverted += report.reverted;
        outcome.culled_steps += report.culled_steps;
        outcome.culled_vertices += report.culled_vertices;
        outcome.steps += report.steps;
        outcome.remesh_culled += report.remesh.culled;
    }
    mesh.validate().unwrap();
    outcome.digest = mesh.digest();
    outcome
}

/// Runs `strokes` culled and not; they must end identical. Returns the culled run.
fn assert_culling_changes_nothing(
    name: &str,
    mesh: &Mesh,
    strokes: &[Stroke],
    remeshing: Remeshing,
) -> Run {
    let culled = run(mesh, strokes, remeshing, true);
    let searched = run(mesh, strokes, remeshing, false);
    assert_eq!(
        (
            searched.culled_steps,
            searched.culled_vertices,
            searched.remesh_culled
        ),
        (0, 0, 0),
        "{name}: culling off still culled"
    );
    assert_eq!(
        (&culled.digest, culled.clamped, culled.reverted),
        (&searched.digest, searched.clamped, searched.reverted),
        "{name}: culling changed the result"
    );
    eprintln!(
        "{name}: {} steps, {} culled, {} vertex searches culled, {} clamped, {} undone, \
         {} remeshing edits vouched for",
        culled.steps,
        culled.culled_steps,
        culled.culled_vertices,
        culled.clamped,
        culled.reverted,
        culled.remesh_culled
    );
    culled
}

/// A draw stroke on layer 0 of `(radius, strength)` through `positions` at full pressure,
/// pushing along `normal` (or the brush frame's).
fn draw(
    (radius, strength): (f32, f32),
    positions: impl Iterator<Item = Vec3>,
    normal: Option<Vec3>,
) -> Stroke {
    Stroke {
        paint: None,
        brush: Brush {
            kind: BrushKind::Draw,
            radius,
            strength,
            falloff: Falloff::Smooth,
            invert: false,
        },
        layers: vec![0],
        spacing: 0.25,
        symmetry: None,
        samples: positions
            .map(|position| Sample {
                position,
                pressure: 1.0,
                normal,
            })
            .collect(),
    }
}

#[test]
fn a_plain_draw_on_a_flat_sheet_is_culled() {
    // Wide enough that a stroke's region lies farther than a sheet zone's margin from the rim.
    let mesh = scene(SceneKind::Plane, 40_000);
    let mut strokes = script(&mesh, BrushMix::StraightDraw, 4);
    // And three full-strength draws along the middle, which stretch edges out of the band.
    let (lo, hi) = mesh.bounds().unwrap();
    let at = |u: f32| lo.lerp(hi, u).with_y(0.5 * (lo.y + hi.y));
    let middle = || (0..24).map(|i| at(0.3 + 0.4 * i as f32 / 23.0));
    strokes.extend((0..3).map(|_| draw((0.1 * (hi.x - lo.x), 1.0), middle(), None)));
    let run = assert_culling_changes_nothing("flat sheet", &mesh, &strokes, Remeshing::AfterStroke);
    // Only the steps whose region reaches the sheet's rim are searched.
    assert!(
        run.culled_steps * 2 > run.steps,
        "a flat sheet is a sheet: {run:?}"
    );
    // And the remesh after the middle's draws is a sheet zone's, which vouches for its edits.
    assert!(run.remesh_culled > 0, "{run:?}");
}

#[test]
fn a_sheet_folded_onto_itself_collides_the_same() {
    // A hairpin: the sheet runs along x, turns over a half circle and comes back above
    // itself, three edge lengths higher; draws on the upper half push it into the lower one.
    let flat = scene(SceneKind::Plane, 6_000);
    let edge = flat.mean_edge_length();
    let gap = 3.0 * edge;
    let turn = std::f32::consts::PI * gap / 2.0;
    let straight = (1.0 - turn) / 2.0;
    let mesh = reshaped(flat, |u, v| {
        let t = u;
        if t < straight {
            Vec3::new(t, v, 0.0)
        } else if t < straight + turn {
            let angle = (t - straight) / (gap / 2.0);
            Vec3::new(
                straight + gap / 2.0 * angle.sin(),
                v,
                gap / 2.0 * (1.0 - angle.cos()),
            )
        } else {
            Vec3::new(straight - (t - straight - turn), v, gap)
        }
    });
    // Narrower than the gap, so that the brush moves the upper half only, back and forth
    // over the same stretch until it meets the lower one.
    let draw_down = |y: f32| {
        let to = |k: usize| Vec3::new(0.2 + 0.1 * ((k % 8) as f32 / 7.0), y, gap);
        draw((0.8 * gap, 1.0), (0..40).map(to), Some(-Vec3::Z))
    };
    let strokes: Vec<Stroke> = [0.3, 0.5, 0.7].map(draw_down).into();
    let run = assert_culling_changes_nothing("folded sheet", &mesh, &strokes, Remeshing::Off);
    assert!(
        run.clamped > 0,
        "the fold must collide with itself: {run:?}"
    );
}

#[test]
fn a_steep_ridge_is_a_sheet_searched_only_where_its_vertices_need_it() {
    // A ridge across the sheet with flanks at up to 58°: its normals fit in a cone well
    // under 90°, so it projects one-to-one (a sheet), but too wide a cone for the bound
    // that clears the proximity clamp's search of the whole region (cos θ·(r + 1)·ρ ≥ d).
    // Draws along its crest (the bench's plane after a few passes over the same rows) then
    // skip the backstop's search, and the clamp's where a vertex's own neighbourhood
    // clears it.
    let flat = scene(SceneKind::Plane, 6_000);
    let mesh = reshaped(flat, |u, v| {
        let across = (u - 0.5) / 0.1;
        Vec3::new(u, v, 0.17 * (-across * across).exp())
    });
    let along_the_crest = |x: f32| {
        let to = |k: usize| Vec3::new(x, 0.3 + 0.4 * k as f32 / 11.0, 0.17);
        draw((0.15, 0.3), (0..12).map(to), None)
    };
    let strokes: Vec<Stroke> = [0.5, 0.47, 0.53].map(along_the_crest).into();
    let run = assert_culling_changes_nothing("steep ridge", &mesh, &strokes, Remeshing::Off);
    assert!(
        run.culled_steps * 2 > run.steps,
        "a ridge is a sheet: {run:?}"
    );
    assert!(
        run.culled_vertices > 0,
        "the ridge's vertices clear by their neighbourhood: {run:?}"
    );
}

#[test]
fn a_narrow_groove_is_searched_where_its_walls_come_close() {
    // A V-shaped groove with walls at 79° in a flat sheet: still one-to-one along the
    // vertical, so a sheet, but too steep to be clear as a whole. Draws pushing its left wall
    // sideways into the right one must be clamped exactly as unculled ones, where the wall's
    // vertices come within the collision distance of the other wall's faces beyond their
    // exclusion ring, while the flat sheet beside the groove clears by its neighbourhood.
    let flat = scene(SceneKind::Plane, 6_000);
    let mesh = reshaped(flat, |u, v| {
        let across = ((u - 0.5) / 0.04).abs();
        Vec3::new(u, v, -0.2 * (1.0 - across).max(0.0))
    });
    // Down the left wall, where it is as deep as the groove is narrow, back and forth.
    let into_the_far_wall = |depth: f32| {
        let along = |k: usize| 0.4 + 0.2 * ((k % 8) as f32 / 7.0);
        let to = |k: usize| Vec3::new(0.485, along(k), depth);
        draw((0.03, 1.0), (0..32).map(to), Some(Vec3::X))
    };
    let strokes: Vec<Stroke> = [-0.13, -0.12, -0.14].map(into_the_far_wall).into();
    let run = assert_culling_changes_nothing("narrow groove", &mesh, &strokes, Remeshing::Off);
    assert!(run.clamped > 0, "the groove's walls must meet: {run:?}");
    assert!(
        run.culled_vertices > 0,
        "the flat sheet around the groove clears by its neighbourhood: {run:?}"
    );
}

#[test]
fn crumpled_pinched_twisted_and_creased_sheets_end_the_same() {
    let flat = scene(SceneKind::Plane, 5_000);
    let edge = flat.mean_edge_length();
    let crumpled = reshaped(flat.clone(), |u, v| {
        let tau = std::f32::consts::TAU;
        Vec3::new(
            u,
            v,
            4.0 * edge * (tau * 3.0 * u).sin() * (tau * 2.5 * v).sin(),
        )
    });
    for (name, mesh) in [
        ("torture on a flat sheet", flat),
        ("crumpled sheet", crumpled),
    ] {
        let strokes = script(&mesh, BrushMix::Torture, 16);
        let kinds: Vec<BrushKind> = strokes.iter().map(|s| s.brush.kind).collect();
        assert!(
            [BrushKind::Pinch, BrushKind::Twist, BrushKind::Crease]
                .iter()
                .any(|k| kinds.contains(k)),
            "{name}: the torture mix should pinch, twist or crease: {kinds:?}"
        );
        assert_culling_changes_nothing(name, &mesh, &strokes, Remeshing::Off);
    }
}

/// Remeshed after each stroke, a sheet's zones vouch for the remesher's edits, yet keep each
/// moved vertex from the sheet's own faces beyond its exclusion ring as the full checks do,
/// where pinches and creases press the sheet together: the same mesh.
#[test]
fn remeshing_after_torture_on_a_wide_sheet_ends_the_same() {
    let mesh = scene(SceneKind::Plane, 30_000);
    let strokes = script(&mesh, BrushMix::Torture, 12);
    let name = "torture on a wide sheet, remeshed";
    let run = assert_culling_changes_nothing(name, &mesh, &strokes, Remeshing::AfterStroke);
    assert!(run.remesh_culled > 0, "{run:?}");
}

#[test]
fn a_closed_sphere_and_a_layered_material_end_the_same() {
    let sphere = scene(SceneKind::Sphere, 5_000);
    let strokes = script(&sphere, BrushMix::InflateGrab, 10);
    assert_culling_changes_nothing("sphere", &sphere, &strokes, Remeshing::AfterStroke);
    let plaster = scene(SceneKind::Plaster, 6_000);
    let strokes = script(&plaster, BrushMix::Torture, 14);
    let run = assert_culling_changes_nothing("plaster", &plaster, &strokes, Remeshing::AfterStroke);
    assert!(run.clamped > 0, "plaster's layers must collide: {run:?}");
}
