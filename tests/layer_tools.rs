//! The layer tools (offset duplicate, delete) on the three materials and a closed sphere: a
//! valid mesh with nothing crossing, the layers and components expected, a copy at the mesh's
//! edge length and the offset from its source, and every tool undone bit for bit.

mod common;

use glam::Vec3;
use slayer::collide::find_intersections;
use slayer::geom::point_triangle_distance_squared;
use slayer::mesh::{LayerId, Mesh};
use slayer::scene::{SceneKind, SceneSpec, generate};
use slayer::session::Session;
use slayer::tools::{CutSettings, DeleteTarget, DuplicateSettings, Selection, ToolError};

fn scene(kind: SceneKind, triangles: usize) -> Mesh {
    generate(&SceneSpec {
        kind,
        triangles,
        seed: 1,
    })
    .unwrap()
}

/// A live vertex of `layer` with no vertex of a layer above it (nor the layer's rim) within
/// `clear` across the xy plane: where a lifted copy meets nothing.
fn open_spot(mesh: &Mesh, layer: LayerId, clear: f32) -> u32 {
    let layers = mesh.vertex_layers();
    let live = |v: u32| mesh.is_vertex_live(v);
    let blockers: Vec<Vec3> = (0..mesh.vertex_count() as u32)
        .filter(|&v| {
            live(v)
                && (layers[v as usize] > layer
                    || (layers[v as usize] == layer && mesh.is_boundary_vertex(v)))
        })
        .map(|v| mesh.positions()[v as usize])
        .collect();
    (0..mesh.vertex_count() as u32)
        .filter(|&v| live(v) && layers[v as usize] == layer)
        .find(|&v| {
            let p = mesh.positions()[v as usize];
            blockers
                .iter()
                .all(|b| (b.truncate() - p.truncate()).length() > clear)
        })
        .unwrap_or_else(|| panic!("no open spot on layer {layer}"))
}

/// Masks the vertices of `layer` within `radius` of `centre`'s vertex, as a session edit.
fn mask_disc(session: &mut Session, layer: LayerId, centre: u32, radius: f32) {
    let mut edit = session.edit("mask disc");
    let mesh = edit.mesh();
    let c = mesh.positions()[centre as usize];
    let inside: Vec<bool> = (0..mesh.vertex_count())
        .map(|v| mesh.vertex_layers()[v] == layer && mesh.positions()[v].distance(c) <= radius)
        .collect();
    for (flags, inside) in mesh.flags_mut().iter_mut().zip(inside) {
        if inside {
            flags.set_mask(1.0);
        }
    }
    edit.commit();
}

/// The distance from `p` to the nearest live face of `layer`.
fn distance_to_layer(mesh: &Mesh, layer: LayerId, p: Vec3) -> f32 {
    (0..mesh.face_count())
        .filter(|&f| !mesh.is_face_dead(f) && mesh.face_layers()[f] == layer)
        .map(|f| {
            let [a, b, c] = mesh.face_positions(f);
            point_triangle_distance_squared(p, a, b, c)
        })
        .fold(f32::INFINITY, f32::min)
        .sqrt()
}

/// Runs a duplicate through the session and checks what every duplicate must be; returns the
/// new layer's vertices.
fn duplicate_and_check(
    session: &mut Session,
    selection: Selection,
    settings: &DuplicateSettings,
) -> Vec<u32> {
    let before = session.mesh().digest();
    let layers_before = session.mesh().layer_count();
    let (report, recorded) = session.duplicate(selection, settings).unwrap();
    assert!(recorded.changed);
    let mesh = session.mesh();
    mesh.validate().unwrap();
    assert_eq!(find_intersections(mesh).total(), 0, "nothing crosses");
    assert_eq!(mesh.layer_count(), layers_before + 1);
    assert_eq!(report.layer as usize, layers_before);
    assert_eq!(session.layers().len(), layers_before + 1);
    let copy = mesh.with_layers(&[report.layer]).unwrap();
    let cv = copy.edge_length_stats().coefficient_of_variation();
    assert!(cv <= 0.15, "the copy's edge cv is {cv}");
    let ratio = copy.mean_edge_length() / settings.edge;
    assert!((0.8..1.25).contains(&ratio), "the copy's edge is {ratio} L");
    let new: Vec<u32> = (0..mesh.vertex_count() as u32)
        .filter(|&v| mesh.is_vertex_live(v) && mesh.vertex_layers()[v as usize] == report.layer)
        .collect();
    for &v in &new {
        let brdf = mesh.brdfs()[v as usize];
        assert!(brdf.is_finite());
        assert_eq!(brdf, settings.material);
    }
    assert!(mesh.brdfs().iter().all(|b| b.is_finite()));
    let after = mesh.digest();
    session.undo().unwrap();
    assert_eq!(session.mesh().digest(), before, "undo restores the mesh");
    assert_eq!(session.layers().len(), layers_before);
    session.redo().unwrap();
    assert_eq!(session.mesh().digest(), after, "redo makes it again");
    new
}

/// The closed components of `layer`.
fn closed_on(mesh: &Mesh, layer: LayerId) -> Vec<slayer::mesh::ClosedComponent> {
    let mut closed = mesh.closed_components();
    closed.retain(|c| c.layer == layer);
    closed
}

/// Every vertex of the copy lies within [0.9, 1.1] × the offset of its source layer.
fn assert_offset(mesh: &Mesh, new: &[u32], source: LayerId, offset: f32) {
    for &v in new.iter().step_by(new.len().div_ceil(400).max(1)) {
        let d = distance_to_layer(mesh, source, mesh.positions()[v as usize]);
        assert!(
            (0.9 * offset..=1.1 * offset).contains(&d),
            "vertex {v} is {} offsets from its source",
            d / offset
        );
    }
}

#[test]
fn a_masked_part_of_each_material_is_copied_above_itself() {
    // Bark's plates are narrow between their cracks: a smaller disc.
    for (kind, layer, edges) in [
        (SceneKind::Plaster, 1, 4.0),
        (SceneKind::Bark, 2, 2.5),
        (SceneKind::Metal, 1, 4.0),
    ] {
        let mut session = Session::new(scene(kind, 20_000));
        let edge = session.mesh().mean_edge_length();
        let radius = edges * edge;
        let centre = open_spot(session.mesh(), layer, radius + 1.5 * edge);
        mask_disc(&mut session, layer, centre, radius);
        let material = slayer::material::RED_PAINT.brdf;
        let settings = DuplicateSettings::for_mesh(session.mesh(), "copy", material);
        let new = duplicate_and_check(&mut session, Selection::Masked(layer), &settings);
        let mesh = session.mesh();
        let components = mesh.components();
        let new_layer = mesh.layer_count() as u32 - 1;
        assert_eq!(
            components.per_layer(mesh.layer_count())[new_layer as usize],
            1,
            "{kind:?}"
        );
        assert_offset(mesh, &new, layer, settings.offset);
    }
}

#[test]
fn a_closed_sphere_is_copied_as_a_sheet_and_as_a_shell() {
    let mut session = Session::new(scene(SceneKind::Sphere, 5_000));
    let settings = DuplicateSettings::for_mesh(session.mesh(), "skin", slayer::material::RUST.brdf);
    let new = duplicate_and_check(&mut session, Selection::Layer(0), &settings);
    assert_offset(session.mesh(), &new, 0, settings.offset);

    let mut session = Session::new(scene(SceneKind::Sphere, 5_000));
    let mut shell = settings.clone();
    shell.thickness = Some(1.5 * settings.edge);
    shell.name = "shell".into();
    duplicate_and_check(&mut session, Selection::Component(0), &shell);
    let closed = closed_on(session.mesh(), 1);
    assert_eq!(
        closed.len(),
        2,
        "a shell of a closed surface is two closed surfaces"
    );
    // The outer faces outward, the inner inward: their volumes have opposite signs.
    assert!(closed[0].volume * closed[1].volume < 0.0);
}

#[test]
fn a_sheet_thickened_is_one_closed_shell() {
    let mut session = Session::new(scene(SceneKind::Plaster, 20_000));
    let edge = session.mesh().mean_edge_length();
    let centre = open_spot(session.mesh(), 1, 6.0 * edge);
    mask_disc(&mut session, 1, centre, 4.0 * edge);
    let mut settings =
        DuplicateSettings::for_mesh(session.mesh(), "chip", slayer::material::PAINT.brdf);
    settings.thickness = Some(2.0 * edge);
    duplicate_and_check(&mut session, Selection::Masked(1), &settings);
    let shells = closed_on(session.mesh(), 3);
    assert_eq!(
        shells.len(),
        1,
        "sheet, band and inner sheet make one closed surface"
    );
    assert!(shells[0].volume > 0.0, "it winds outward");
}

#[test]
fn a_copy_that_cannot_be_placed_is_refused_and_changes_nothing() {
    let mut session = Session::new(scene(SceneKind::Plaster, 20_000));
    let before = session.mesh().digest();
    let entries = session.history().entries().len();
    let mut settings =
        DuplicateSettings::for_mesh(session.mesh(), "copy", slayer::material::PAINT.brdf);
    // The base lifted into the paint above it, as a shell thicker than the room there.
    settings.thickness = Some(20.0 * settings.edge);
    let refused = session
        .duplicate(Selection::Layer(0), &settings)
        .unwrap_err();
    assert!(matches!(refused, ToolError::NoRoom { .. }), "{refused}");
    settings.thickness = None;
    settings.offset = f32::NAN;
    assert!(matches!(
        session.duplicate(Selection::Layer(0), &settings),
        Err(ToolError::BadLength { .. })
    ));
    assert!(matches!(
        session.duplicate(
            Selection::Masked(1),
            &DuplicateSettings::for_mesh(session.mesh(), "x", slayer::material::PAINT.brdf)
        ),
        Err(ToolError::EmptySelection(_))
    ));
    assert_eq!(session.mesh().digest(), before);
    assert_eq!(
        session.history().entries().len(),
        entries,
        "nothing recorded"
    );
}

#[test]
fn each_material_loses_its_smallest_pieces_and_top_layer_and_gets_them_back() {
    for kind in [SceneKind::Plaster, SceneKind::Bark, SceneKind::Metal] {
        let mut session = Session::new(scene(kind, 20_000));
        let (start, layers) = (session.mesh().digest(), session.mesh().layer_count());
        let components = session.mesh().components().count();
        session.delete(DeleteTarget::Smallest(2)).unwrap();
        session
            .delete(DeleteTarget::Layer(layers as LayerId - 1))
            .unwrap();
        let mesh = session.mesh();
        mesh.validate().unwrap();
        assert_eq!(find_intersections(mesh).total(), 0);
        assert_eq!(mesh.layer_count(), layers - 1, "{kind:?}");
        assert!(mesh.components().count() < components - 1, "{kind:?}");
        assert!(mesh.brdfs().iter().all(|b| b.is_finite()));
        session.undo().unwrap();
        session.undo().unwrap();
        assert_eq!(session.mesh().digest(), start, "{kind:?}");
    }
}

#[test]
fn deleting_components_and_layers_compacts_and_undoes() {
    let mut session = Session::new(scene(SceneKind::Plaster, 20_000));
    let mesh = session.mesh();
    let (start, layers, components) =
        (mesh.digest(), mesh.layer_count(), mesh.components().count());
    let (deleted, _) = session.delete(DeleteTarget::Smallest(3)).unwrap();
    assert_eq!(deleted.components, 3);
    let mesh = session.mesh();
    mesh.validate().unwrap();
    assert_eq!(mesh.components().count(), components - 3);
    assert_eq!(mesh.live_face_count(), mesh.face_count(), "compacted");
    let small = mesh.components().size.iter().filter(|&&s| s < 40).count();
    let (deleted, _) = session.delete(DeleteTarget::Under(40)).unwrap();
    assert_eq!(deleted.components, small);
    let names: Vec<String> = session.mesh().layer_names().to_vec();
    session.delete(DeleteTarget::Layer(1)).unwrap();
    let mesh = session.mesh();
    mesh.validate().unwrap();
    assert_eq!(mesh.layer_count(), layers - 1);
    assert_eq!(mesh.layer_names(), &[names[0].clone(), names[2].clone()]);
    assert_eq!(session.layers().len(), layers - 1);
    assert!(
        mesh.face_layers()
            .iter()
            .all(|&l| (l as usize) < layers - 1)
    );
    assert_eq!(find_intersections(mesh).total(), 0);
    for _ in 0..3 {
        session.undo().unwrap();
    }
    assert_eq!(
        session.mesh().digest(),
        start,
        "three undos restore the scene"
    );
    assert_eq!(session.layers().len(), layers);

    // A pipeline prepared for the mesh before the tools sculpts the mesh they left.
    let mut pipeline = slayer::pipeline::Pipeline::new(Default::default());
    let script = slayer::bench::generate_script(session.mesh(), &Default::default());
    let strokes = script.resolve(session.mesh(), "script").unwrap();
    session.apply_stroke(&mut pipeline, &strokes[0]).unwrap();
    session.delete(DeleteTarget::Layer(2)).unwrap();
    let script = slayer::bench::generate_script(session.mesh(), &Default::default());
    let strokes = script.resolve(session.mesh(), "script").unwrap();
    session.apply_stroke(&mut pipeline, &strokes[1]).unwrap();
    session.mesh().validate().unwrap();
    assert_eq!(find_intersections(session.mesh()).total(), 0);

    let refused = session.delete(DeleteTarget::Component(999)).unwrap_err();
    assert!(matches!(refused, ToolError::NoSuchComponent { .. }));
    let mut sphere = Session::new(scene(SceneKind::Sphere, 2_000));
    let refused = sphere.delete(DeleteTarget::Layer(0)).unwrap_err();
    assert!(matches!(refused, ToolError::WouldEmpty(_)), "{refused}");
    assert!(sphere.history().entries().is_empty());
}

#[test]
fn the_command_line_lists_duplicates_and_deletes() {
    use common::{arg, slayer, text};
    let dir = common::scratch("layer-tools");
    let input = dir.join("plaster.ply");
    common::write_scene("plaster", 20_000, &[], &input);
    let out = slayer(&["layer", "list", arg(&input), "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let listed: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(listed.as_array().unwrap().len(), 3);
    assert_eq!(listed[1]["name"], "paint");

    let session = dir.join("copy.slayer");
    let out = slayer(&[
        "layer",
        "duplicate",
        arg(&input),
        "-o",
        arg(&session),
        "--layer",
        "paint",
        "--material",
        "rust",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("new layer 3 `paint copy`"),
        "{}",
        text(&out.stdout)
    );
    let undone = dir.join("undone.ply");
    let out = slayer(&["undo", arg(&session), "-o", arg(&undone)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let (a, b) = (
        slayer::io::read_mesh(&input).unwrap(),
        slayer::io::read_mesh(&undone).unwrap(),
    );
    assert_eq!(
        a.digest(),
        b.digest(),
        "undoing the tool gives the input back"
    );

    let deleted = dir.join("deleted.ply");
    let out = slayer(&[
        "layer",
        "delete",
        arg(&session),
        "-o",
        arg(&deleted),
        "--layer",
        "flakes",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let mesh = slayer::io::read_mesh(&deleted).unwrap();
    assert_eq!(mesh.layer_names(), &["plaster", "paint", "paint copy"]);

    let refused = slayer(&[
        "layer",
        "delete",
        arg(&input),
        "-o",
        arg(&input),
        "--smallest",
        "1",
    ]);
    common::assert_one_line_error(&refused, &["the output is the input file"]);
    let refused = slayer(&[
        "layer",
        "duplicate",
        arg(&input),
        "-o",
        arg(&dir.join("x.ply")),
        "--component",
        "99",
    ]);
    common::assert_one_line_error(&refused, &["component 99 does not exist"]);
    assert!(!dir.join("x.ply").exists());
}

/// A stroke across `layer` along x at the middle of its y range, through its own vertices
/// (points on the surface, as a pick would give), from `from` to `to` of its x range.
fn stroke_across(mesh: &Mesh, layer: LayerId, (from, to): (f32, f32)) -> Vec<Vec3> {
    let edge = mesh.mean_edge_length();
    let on_layer: Vec<Vec3> = (0..mesh.vertex_count() as u32)
        .filter(|&v| mesh.is_vertex_live(v) && mesh.vertex_layers()[v as usize] == layer)
        .map(|v| mesh.positions()[v as usize])
        .collect();
    let (lo, hi) = on_layer
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), &p| {
            (a.min(p), b.max(p))
        });
    let y = 0.5 * (lo.y + hi.y);
    let mut band: Vec<Vec3> = on_layer
        .into_iter()
        .filter(|p| (p.y - y).abs() < 0.6 * edge)
        .collect();
    band.sort_by(|a, b| a.x.total_cmp(&b.x));
    let (x0, x1) = (lo.x + from * (hi.x - lo.x), lo.x + to * (hi.x - lo.x));
    band.into_iter()
        .filter(|p| (x0..=x1).contains(&p.x))
        .step_by(3)
        .collect()
}

/// Cuts through the session and checks what every cut must be.
fn cut_and_check(
    session: &mut Session,
    stroke: &[Vec3],
    layers: &[LayerId],
) -> slayer::tools::CutReport {
    let before = session.mesh().digest();
    let settings = CutSettings::for_mesh(session.mesh(), layers);
    let (report, _) = session.cut(stroke, &settings).unwrap();
    let mesh = session.mesh();
    mesh.validate().unwrap();
    assert_eq!(find_intersections(mesh).total(), 0, "the sides are apart");
    assert!(report.path_edges > 0 && report.duplicated > 0, "{report:?}");
    assert!(
        report.farthest_from_stroke <= 0.5 * settings.edge,
        "the path strays {} edges from the stroke",
        report.farthest_from_stroke / settings.edge
    );
    assert!(mesh.brdfs().iter().all(|b| b.is_finite()));
    assert!(
        mesh.face_layers()
            .iter()
            .all(|&l| (l as usize) < mesh.layer_count())
    );
    let after = mesh.digest();
    session.undo().unwrap();
    assert_eq!(session.mesh().digest(), before, "undo restores the mesh");
    session.redo().unwrap();
    assert_eq!(session.mesh().digest(), after);
    report
}

#[test]
fn a_closed_cut_detaches_a_piece_and_an_open_one_makes_a_slit() {
    let sphere = scene(SceneKind::Sphere, 5_000);
    let ring: Vec<Vec3> = (0..=24)
        .map(|k| {
            let a = k as f32 / 24.0 * std::f32::consts::TAU;
            Vec3::new(0.2 * a.cos(), 0.2 * a.sin(), 0.46)
        })
        .collect();
    let mut session = Session::new(sphere.clone());
    let report = cut_and_check(&mut session, &ring, &[0]);
    assert_eq!((report.components_before, report.components_after), (1, 2));
    assert_eq!(
        session.mesh().closed_components().len(),
        0,
        "both pieces are open"
    );

    let mut session = Session::new(sphere);
    let line = [Vec3::new(-0.3, -0.05, 0.45), Vec3::new(0.3, 0.1, 0.45)];
    let report = cut_and_check(&mut session, &line, &[0]);
    assert_eq!(report.components_after, 1, "a slit keeps the sphere whole");
    assert!(report.splits > 0, "edges were split to follow the stroke");
}

#[test]
fn each_material_is_cut_across_its_top_layer() {
    for (kind, layer) in [
        (SceneKind::Plaster, 1),
        (SceneKind::Bark, 1),
        (SceneKind::Metal, 0),
    ] {
        let mut session = Session::new(scene(kind, 20_000));
        let stroke = stroke_across(session.mesh(), layer, (0.2, 0.8));
        let report = cut_and_check(&mut session, &stroke, &[layer]);
        let faces = session.mesh().faces_per_layer();
        assert!(faces[layer as usize] > 0, "{kind:?}: {report:?}");
    }
    // A stroke nowhere near the layer is refused and changes nothing.
    let mut session = Session::new(scene(SceneKind::Plaster, 20_000));
    let before = session.mesh().digest();
    let far = [Vec3::splat(50.0), Vec3::splat(51.0)];
    let refused = session
        .cut(&far, &CutSettings::for_mesh(session.mesh(), &[0]))
        .unwrap_err();
    assert!(matches!(refused, ToolError::EmptySelection(_)), "{refused}");
    assert_eq!(session.mesh().digest(), before);
    assert!(session.history().entries().is_empty());
}

/// A closed outline of `n` points on a circle of `radius` around `centre`'s vertex, on `layer`'s
/// surface as the vertices near each point give it.
fn outline_around(mesh: &Mesh, layer: LayerId, centre: u32, radius: f32, n: usize) -> Vec<Vec3> {
    let c = mesh.positions()[centre as usize];
    (0..=n)
        .map(|k| {
            let a = k as f32 / n as f32 * std::f32::consts::TAU;
            let target = c + Vec3::new(radius * a.cos(), radius * a.sin(), 0.0);
            (0..mesh.vertex_count() as u32)
                .filter(|&v| mesh.is_vertex_live(v) && mesh.vertex_layers()[v as usize] == layer)
                .map(|v| mesh.positions()[v as usize])
                .min_by(|p, q| {
                    (p.truncate() - target.truncate())
                        .length()
                        .total_cmp(&(q.truncate() - target.truncate()).length())
                })
                .unwrap()
        })
        .collect()
}

/// Runs a patch through the session and checks what every patch must be.
fn patch_and_check(session: &mut Session, outline: &[Vec3], layer: LayerId) {
    let before = session.mesh().digest();
    let layers = session.mesh().layer_count();
    let settings =
        DuplicateSettings::for_mesh(session.mesh(), "patch", slayer::material::RUST.brdf);
    let (report, _) = session.patch(outline, layer, &settings).unwrap();
    let mesh = session.mesh();
    mesh.validate().unwrap();
    assert_eq!(find_intersections(mesh).total(), 0);
    assert_eq!(mesh.layer_count(), layers + 1);
    assert_eq!(
        mesh.components().per_layer(layers + 1)[layers],
        1,
        "one sheet"
    );
    let copy = mesh.with_layers(&[report.layer]).unwrap();
    let cv = copy.edge_length_stats().coefficient_of_variation();
    assert!(cv <= 0.15, "the patch's edge cv is {cv}");
    let new: Vec<u32> = (0..mesh.vertex_count() as u32)
        .filter(|&v| mesh.is_vertex_live(v) && mesh.vertex_layers()[v as usize] == report.layer)
        .collect();
    assert!(
        new.iter()
            .all(|&v| mesh.brdfs()[v as usize] == settings.material)
    );
    assert_offset(mesh, &new, layer, settings.offset);
    let after = mesh.digest();
    session.undo().unwrap();
    assert_eq!(session.mesh().digest(), before);
    session.redo().unwrap();
    assert_eq!(session.mesh().digest(), after);
}

#[test]
fn a_closed_stroke_becomes_a_coons_patch_above_the_surface() {
    let mut session = Session::new(scene(SceneKind::Sphere, 5_000));
    let ring: Vec<Vec3> = (0..=16)
        .map(|k| {
            let a = k as f32 / 16.0 * std::f32::consts::TAU;
            Vec3::new(0.2 * a.cos(), 0.2 * a.sin(), 0.45)
        })
        .collect();
    patch_and_check(&mut session, &ring, 0);
    for (kind, layer) in [
        (SceneKind::Plaster, 1),
        (SceneKind::Bark, 2),
        (SceneKind::Metal, 1),
    ] {
        let mut session = Session::new(scene(kind, 20_000));
        let edge = session.mesh().mean_edge_length();
        let radius = if kind == SceneKind::Bark { 2.5 } else { 4.0 } * edge;
        let centre = open_spot(session.mesh(), layer, radius + 1.5 * edge);
        let outline = outline_around(session.mesh(), layer, centre, radius, 12);
        patch_and_check(&mut session, &outline, layer);
    }
}

/// Past a thousand faces a patch is laid out as a triangular lattice, counted on its middle
/// as well as its sides and shortened by the stretch lifting gives it. On a plane its edges
/// come out more even than the remesher leaves a quad layout (a round patch: cv 0.10 against
/// 0.13; the story's 640K outlines: 0.05 against 0.17). A cap on a sphere is projected from
/// the flat patch its outline spans, 1.25× stretched in the middle and 0.8× at the rim, which
/// neither layout undoes (0.13 as a lattice, 0.12 as quads): it is held to the 0.15.
#[test]
fn a_large_patch_is_laid_out_as_an_even_lattice() {
    let plane = scene(SceneKind::Plane, 40_000);
    let edge = plane.mean_edge_length();
    let circle = |centre: Vec3, radius: f32, z: f32| -> Vec<Vec3> {
        (0..=24)
            .map(|k| {
                let a = k as f32 / 24.0 * std::f32::consts::TAU;
                centre + Vec3::new(radius * a.cos(), radius * a.sin(), z)
            })
            .collect()
    };
    let sphere = scene(SceneKind::Sphere, 40_000);
    let round_on_plane = circle(Vec3::new(0.5, 0.5, 0.0), 20.0 * edge, 0.0);
    let cases = [
        ("plane", plane, round_on_plane, 0.12),
        ("sphere", sphere, circle(Vec3::ZERO, 0.3, 0.4), 0.15),
    ];
    for (name, mesh, outline, most_cv) in cases {
        let mut session = Session::new(mesh);
        patch_and_check(&mut session, &outline, 0);
        let mesh = session.mesh();
        let copy = mesh
            .with_layers(&[mesh.layer_count() as LayerId - 1])
            .unwrap();
        let quality = slayer::remesh::Quality::of(&copy);
        eprintln!("{name}: {quality:?}");
        assert!(quality.faces > 1_000, "{name}: {} faces", quality.faces);
        assert!(
            quality.edge_cv <= most_cv,
            "{name}: edge cv {}",
            quality.edge_cv
        );
        assert!(
            quality.smallest_angle.p1 >= 35.0,
            "{name}: {:?}",
            quality.smallest_angle
        );
    }
}

#[test]
fn degenerate_outlines_are_refused_with_the_reason() {
    let mut session = Session::new(scene(SceneKind::Sphere, 5_000));
    let before = session.mesh().digest();
    let settings =
        DuplicateSettings::for_mesh(session.mesh(), "patch", slayer::material::RUST.brdf);
    let circle = |r: f32, turns: f32| -> Vec<Vec3> {
        (0..=16)
            .map(|k| {
                let a = k as f32 / 16.0 * std::f32::consts::TAU * turns;
                Vec3::new(r * a.cos(), r * a.sin(), 0.48)
            })
            .collect()
    };
    let figure_eight: Vec<Vec3> = (0..=32)
        .map(|k| {
            let a = k as f32 / 32.0 * std::f32::consts::TAU;
            Vec3::new(0.2 * a.sin(), 0.1 * (2.0 * a).sin(), 0.45)
        })
        .collect();
    for (outline, why) in [
        (circle(0.02, 1.0), "too short"),
        (circle(0.2, 0.6), "not closed"),
        (figure_eight, "crosses itself"),
        (vec![Vec3::ZERO; 2], "at least four"),
    ] {
        let refused = session.patch(&outline, 0, &settings).unwrap_err();
        assert!(refused.to_string().contains(why), "{why}: {refused}");
    }
    assert_eq!(session.mesh().digest(), before);
    assert!(session.history().entries().is_empty());
}
