//! Issue 22, item 2: a long grab. Remeshed only at the stroke's end, a drag of many radii left
//! edges tens of units long whose splitting compounded (a drag of 10 units over a 2K-face
//! sphere: 15K splits and 12K collapses, 4.9 s of remeshing); and splitting the needle such a
//! drag draws out put new vertices a float's hair off their edges, onto faces pressed
//! together within the exclusion ring (17 crossings). Dragged on past where its needle's
//! sides hold it back, a grab remeshed its whole region at every sample to refuse the same
//! splits again (a drag of 100 units: 2,208 passes, 246K refusals), and clamped the same
//! still vertices at every step (619K clamps); it now lets go of them while the drag keeps
//! its direction. Work is counted here, never timed.

mod common;

use glam::Vec3;
use slayer::brush::BrushKind;
use slayer::collide::find_intersections;
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings, StrokeReport};
use slayer::scene::{SceneKind, SceneSpec, generate};

fn sphere() -> Mesh {
    generate(&SceneSpec {
        kind: SceneKind::Sphere,
        triangles: 2_000,
        seed: 1,
    })
    .unwrap()
}

/// A grab of radius 0.15 caught at the sphere's +x pole and dragged `distance` along +x.
fn drag(mesh: &mut Mesh, distance: f32) -> StrokeReport {
    let pole = mesh
        .positions()
        .iter()
        .copied()
        .fold(Vec3::NEG_INFINITY, |a, p| if p.x > a.x { p } else { a });
    let stroke =
        common::one_brush_stroke(BrushKind::Grab, 0.15, &[pole, pole + Vec3::X * distance]);
    let report = Pipeline::new(PipelineSettings::default())
        .apply_stroke(mesh, &stroke)
        .unwrap();
    mesh.validate().unwrap();
    report
}

/// Splits, collapses and flips: the edits remeshing made.
fn edits(report: &StrokeReport) -> usize {
    report.remesh.splits + report.remesh.collapses + report.remesh.flips
}

#[test]
fn a_long_grab_is_remeshed_as_it_stretches_and_never_crosses() {
    let (mut short, mut long) = (sphere(), sphere());
    let (three, ten) = (drag(&mut short, 3.0), drag(&mut long, 10.0));
    for (mesh, distance) in [(&short, 3), (&long, 10)] {
        let crossings = find_intersections(mesh).total();
        assert_eq!(
            crossings, 0,
            "a grab of {distance} units: {crossings} crossings"
        );
    }
    // The drags reached: the short one all the way, the long one at least 4 units. Past some
    // ten sphere diameters the needle's sides press within the collision distance and hold
    // the grab back, by an amount that swings with the last ulp (5 to 6.6 for this drag).
    let reach = |mesh: &Mesh| {
        mesh.positions()
            .iter()
            .map(|p| p.x)
            .fold(f32::MIN, f32::max)
    };
    assert!(
        reach(&short) > 3.49,
        "a grab of 3 units pulled the surface only to x = {}",
        reach(&short)
    );
    assert!(
        reach(&long) > 4.5,
        "a grab of 10 units pulled the surface only to x = {}",
        reach(&long)
    );
    // Remeshing work in proportion to the drag (50 % slack), not compounding with it.
    let ratio = edits(&ten) as f64 / edits(&three).max(1) as f64;
    assert!(
        ratio <= 1.5 * 10.0 / 3.0,
        "remeshing edits: {} for 3 units, {} for 10 (×{ratio:.1})",
        edits(&three),
        edits(&ten)
    );
}

/// Drags of 10 and 100 units, past where the needle holds the grab; the long one crosses
/// nothing.
fn drags_of_ten_and_a_hundred_units() -> (StrokeReport, StrokeReport) {
    let (mut ten_units, mut hundred) = (sphere(), sphere());
    let (ten, long) = (drag(&mut ten_units, 10.0), drag(&mut hundred, 100.0));
    assert_eq!(find_intersections(&hundred).total(), 0);
    (ten, long)
}

#[test]
fn a_grab_dragged_on_past_where_it_is_held_remeshes_no_more_than_in_proportion() {
    let (ten, long) = drags_of_ten_and_a_hundred_units();
    // Ten times the drag, at most ten times the remeshing refused: every sample tried the
    // needle's edges again, 16,036 and 246,093 (15 times).
    assert!(
        long.remesh.refused <= 10 * ten.remesh.refused.max(1),
        "remeshing refused {} edits for 10 units, {} for 100",
        ten.remesh.refused,
        long.remesh.refused
    );
}

#[test]
fn a_grab_dragged_on_past_where_it_is_held_clamps_no_more_than_in_proportion() {
    let (ten, long) = drags_of_ten_and_a_hundred_units();
    // Ten times the drag, at most ten times the clamps. Clamping the vertices the needle
    // holds again at every step made it 36 times (17,130 and 618,781).
    assert!(
        long.clamped <= 10 * ten.clamped.max(1),
        "clamps: {} for 10 units, {} for 100",
        ten.clamped,
        long.clamped
    );
}

#[test]
fn a_grab_pushed_into_a_layer_and_pulled_back_brings_the_surface_back() {
    let (mut mesh, stroke) = common::grab_pushed_into_a_layer_and_back();
    let report = Pipeline::new(PipelineSettings::default())
        .apply_stroke(&mut mesh, &stroke)
        .unwrap();
    mesh.validate().unwrap();
    assert!(report.clamped > 0, "the push never met the lower sheet");
    assert_eq!(find_intersections(&mesh).total(), 0);
    // The vertices let go rejoined the grab when it turned back. How far the sheet is left
    // below where it began: 47 before grabs let go; letting go for the rest of the stroke
    // left 88.
    let sunk = common::upper_sheet_sunk(&mesh);
    assert!(
        sunk < 60.0,
        "the upper sheet is left {sunk} below where it began"
    );
}
