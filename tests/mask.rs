//! Masks: a weight in [0, 1] per vertex (a half-masked vertex moves half as far, a fully masked
//! one not at all but still collides), painted with the mask brush, set per layer or component,
//! inverted and cleared as undoable session entries, and kept by PLY and the session file.

use glam::Vec3;
use slayer::brush::StrokeFile;
use slayer::collide::find_intersections;
use slayer::mesh::{Mesh, VertexFlags};
use slayer::pipeline::{Pipeline, PipelineSettings, Remeshing};
use slayer::scene::shapes::stacked_sheets;
use slayer::session::{Session, read_session, write_session};

fn no_remeshing() -> Pipeline {
    Pipeline::new(PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    })
}

/// One sample of `brush` at `strength` (inverted when `invert`) at (x, y) on the sheets' top,
/// on every layer, parsed and checked.
fn stroke(
    mesh: &Mesh,
    (brush, strength, invert): (&str, f32, bool),
    at: [f32; 2],
) -> slayer::brush::Stroke {
    let z = mesh.bounds().unwrap().1.z;
    let layers: Vec<u32> = (0..mesh.layer_count() as u32).collect();
    let text = format!(
        r#"{{"strokes": [{{"brush": "{brush}", "radius": 0.3, "strength": {strength},
            "invert": {invert}, "layers": {layers:?},
            "samples": [{{"position": [{x}, {y}, {z}]}}]}}]}}"#,
        x = at[0],
        y = at[1],
    );
    let file = StrokeFile::parse(&text, "t.json").unwrap();
    file.resolve(mesh, "t.json").unwrap().remove(0)
}

fn displacements(before: &Mesh, after: &Mesh) -> Vec<Vec3> {
    before
        .positions()
        .iter()
        .zip(after.positions())
        .map(|(a, b)| *b - *a)
        .collect()
}

#[test]
fn a_half_masked_vertex_moves_half_as_far() {
    let sheets = stacked_sheets(1, 40, 40, 0.05, 0.1);
    let draw = stroke(&sheets, ("draw", 0.3, false), [1.0, 1.0]);
    let mut free = sheets.clone();
    no_remeshing().apply_stroke(&mut free, &draw).unwrap();
    let mut half = sheets.clone();
    for flags in half.flags_mut() {
        flags.set_mask(0.5);
    }
    no_remeshing().apply_stroke(&mut half, &draw).unwrap();
    let factor = half.flags()[0].mask();
    assert!((factor - 0.5).abs() < 0.003, "mask {factor}");
    let (full, halved) = (displacements(&sheets, &free), displacements(&sheets, &half));
    let mut compared = 0;
    for (a, b) in full.iter().zip(&halved) {
        if a.length() > 1e-4 {
            let ratio = b.length() / a.length();
            assert!((ratio - (1.0 - factor)).abs() < 1e-3, "ratio {ratio}");
            compared += 1;
        }
    }
    assert!(compared > 50, "only {compared} vertices moved");
}

#[test]
fn the_mask_brush_masks_and_inverted_unmasks_and_a_masked_vertex_stays() {
    let mut mesh = stacked_sheets(1, 40, 40, 0.05, 0.1);
    let centre = (0..mesh.vertex_count())
        .min_by(|&a, &b| {
            let d = |v: usize| mesh.positions()[v].truncate().distance(glam::Vec2::ONE);
            d(a).total_cmp(&d(b))
        })
        .unwrap();
    let mut pipeline = no_remeshing();
    let mask = stroke(&mesh, ("mask", 1.0, false), [1.0, 1.0]);
    let report = pipeline.apply_stroke(&mut mesh, &mask).unwrap();
    assert!(report.changed.contains(&(centre as u32)));
    assert_eq!(mesh.flags()[centre].mask(), 1.0);
    assert!(mesh.flags()[centre].contains(VertexFlags::MASKED));
    let partial = mesh
        .flags()
        .iter()
        .filter(|f| (0.0..1.0).contains(&f.mask()) && f.mask() > 0.0)
        .count();
    assert!(partial > 10, "the falloff left {partial} partial masks");

    let before = mesh.clone();
    let draw = stroke(&mesh, ("draw", 0.3, false), [1.0, 1.0]);
    pipeline.apply_stroke(&mut mesh, &draw).unwrap();
    assert_eq!(mesh.positions()[centre], before.positions()[centre]);

    let unmask = stroke(&mesh, ("mask", 1.0, true), [1.0, 1.0]);
    pipeline.apply_stroke(&mut mesh, &unmask).unwrap();
    assert_eq!(mesh.flags()[centre].mask(), 0.0);
    let moved_before = mesh.positions()[centre];
    pipeline.apply_stroke(&mut mesh, &draw).unwrap();
    assert_ne!(mesh.positions()[centre], moved_before);
}

#[test]
fn masked_vertices_still_collide() {
    // Three sheets 0.1 apart: the middle one fully masked, the bottom one pushed up into it.
    let input = stacked_sheets(3, 30, 30, 0.05, 0.1);
    let mut session = Session::new(input.clone());
    session.mask_layer(1, 1.0).unwrap();
    let mut pipeline = no_remeshing();
    let z = 0.02;
    let text = format!(
        r#"{{"strokes": [{{"brush": "draw", "radius": 0.4, "strength": 1.0, "layers": [0, 1],
            "samples": [{{"position": [0.7, 0.7, {z}]}}, {{"position": [0.8, 0.7, {z}]}},
                        {{"position": [0.9, 0.7, {z}]}}]}}]}}"#
    );
    let strokes = StrokeFile::parse(&text, "t")
        .unwrap()
        .resolve(session.mesh(), "t")
        .unwrap();
    let (report, _) = session.apply_stroke(&mut pipeline, &strokes[0]).unwrap();
    assert!(
        report.clamped > 0,
        "the pushed sheet never met the masked one"
    );
    let mesh = session.mesh();
    assert_eq!(find_intersections(mesh).total(), 0);
    for v in 0..mesh.vertex_count() {
        if mesh.vertex_layers()[v] == 1 {
            assert_eq!(
                mesh.positions()[v],
                input.positions()[v],
                "masked vertex {v} moved"
            );
        }
    }
}

#[test]
fn mask_edits_are_undoable_and_files_keep_partial_masks() {
    let input = stacked_sheets(2, 20, 20, 0.05, 0.1);
    let mut session = Session::new(input.clone());
    session.mask_layer(0, 0.25).unwrap();
    session.mask_component(input.faces()[0][0], 0.75).unwrap();
    session.invert_mask();
    let masks: Vec<f32> = session.mesh().flags().iter().map(|f| f.mask()).collect();
    assert!(
        masks.iter().any(|&m| (m - 0.25).abs() < 0.003),
        "component 0.75 inverted"
    );
    assert!(masks.contains(&1.0), "unmasked layer 1 inverted to full");
    assert!(session.mask_component(u32::MAX, 1.0).is_err());

    // Files keep every level.
    let ply = slayer::io::encode_mesh(session.mesh(), slayer::io::Format::Ply);
    let back = slayer::io::read_mesh_bytes(&ply, slayer::io::Format::Ply, "m.ply").unwrap();
    assert_eq!(back.flags(), session.mesh().flags());
    assert_eq!(back.digest(), session.mesh().digest());
    let from_session = read_session(&write_session(&session, true), "m.slayer").unwrap();
    assert_eq!(from_session.mesh().flags(), session.mesh().flags());
    // The digest sees a partial mask.
    let mut other = back.clone();
    other.flags_mut()[0].set_mask(0.5);
    assert_ne!(other.digest(), back.digest());

    session.clear_mask();
    assert!(session.mesh().flags().iter().all(|f| f.mask() == 0.0));
    while session.undo().is_some() {}
    assert_eq!(session.mesh().digest(), input.digest());
}

/// Remeshing splits edges inside masked regions: the new vertex takes the mask of the edge
/// where it sits, so what was masked stays masked (and a half-way vertex half-masked).
#[test]
fn a_split_vertex_keeps_the_mask_of_its_edge() {
    let mut mesh = Mesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
        vec![[0, 1, 2], [2, 1, 3]],
        vec![0, 0],
        vec!["sheet".into()],
    )
    .unwrap();
    for (v, mask) in [(0, 1.0), (1, 1.0), (2, 0.0), (3, 1.0)] {
        mesh.flags_mut()[v].set_mask(mask);
    }
    // Corner 2 of face 0 is vertex 2: its opposite edge is (0, 1), both masked.
    let inside = mesh.split_edge(2, 0.5);
    assert_eq!(mesh.flags()[inside as usize].mask(), 1.0);
    // Face 0 is now [0, inside, 2]: its corner 0's opposite edge runs from `inside`
    // (masked) to vertex 2 (not).
    let between = mesh.split_edge(0, 0.5);
    let half = mesh.flags()[between as usize].mask();
    assert!((half - 0.5).abs() <= 1.0 / 255.0, "mask {half}");
    mesh.validate().unwrap();
}
