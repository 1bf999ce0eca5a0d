//! Real-world files: the hand-written corpus in `tests/data/import/` (shapes other tools write)
//! imports with the expected repairs and notes, `--strict` still refuses, colours and materials
//! come in, and any triangle soup at all repairs into a valid mesh.

mod common;

use std::path::{Path, PathBuf};

use common::{arg, assert_one_line_error, scratch, slayer, text, write_scene};
use glam::Vec3;
use proptest::prelude::*;
use slayer::io::{
    Format, ImportOptions, ImportReport, UpAxis, import_bytes, import_mesh, write_mesh,
};
use slayer::mesh::{Brdf, Mesh, Repairs, Soup, repair};

fn corpus(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/import")
        .join(name)
}

fn import(name: &str) -> (Mesh, ImportReport) {
    import_mesh(&corpus(name), &ImportOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn strict(name: &str) -> String {
    import_mesh(&corpus(name), &ImportOptions { strict: true })
        .map(|_| ())
        .expect_err("strict refuses a file that needs repairs")
        .to_string()
}

fn close(a: [f32; 3], b: [f32; 3]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6)
}

#[test]
fn a_textured_obj_from_a_modelling_tool_loads_with_its_materials() {
    let (mesh, report) = import("textured.obj");
    assert_eq!(mesh.layer_names(), ["side"], "a bare `g` starts no layer");
    assert_eq!(mesh.live_face_count(), 4, "two quads, triangulated");
    assert_eq!(
        mesh.live_vertex_count(),
        6,
        "the two materials' halves are one surface"
    );
    assert_eq!(mesh.components().count(), 1);
    assert!(!report.repairs.any(), "{}", report.repairs);
    assert_eq!(
        report.not_kept,
        [
            "4 texture coordinates (`vt`)",
            "1 normals (`vn`; recomputed)",
            "1 line elements (`l`)",
            "texture map `paint.png` of material `red_paint`",
            "opacity (`d`) of material `blue_metal`",
        ]
    );
    // Vertices keep the file's order; each takes the material of the first face using it.
    let red = mesh.brdfs()[0];
    assert!(close(red.diffuse, [0.8, 0.1, 0.1]) && close(red.specular, [0.04; 3]));
    let from_ns = (2.0f32 / (10.0 + 2.0)).sqrt().sqrt();
    assert!(
        (red.roughness - from_ns).abs() < 1e-6,
        "Ns 10 → {}",
        red.roughness
    );
    assert_eq!(mesh.brdfs()[1], red, "v2 is first used by the red quad");
    let blue = mesh.brdfs()[4];
    assert!(close(blue.diffuse, [0.1, 0.1, 0.7]) && close(blue.specular, [0.9; 3]));
    assert_eq!(blue.roughness, 0.25, "`Pr` is our roughness, read exactly");
}

#[test]
fn a_material_library_that_cannot_be_read_is_a_note_not_an_error() {
    let text = std::fs::read(corpus("textured.obj")).unwrap();
    let (mesh, report) =
        import_bytes(&text, Format::Obj, "t.obj", &ImportOptions::default()).unwrap();
    assert_eq!(mesh.live_face_count(), 4);
    assert!(mesh.brdfs().iter().all(|b| *b == Brdf::CLAY));
    assert_eq!(report.notes.len(), 1, "{:?}", report.notes);
    assert!(report.notes[0].starts_with("material library `box.mtl` not read"));
}

#[test]
fn non_manifold_vertices_and_edges_are_split_and_strict_still_refuses() {
    let (mesh, report) = import("bowtie.obj");
    let expected = Repairs {
        non_manifold_vertices: 1,
        ..Repairs::default()
    };
    assert_eq!(report.repairs, expected);
    assert_eq!(
        (mesh.live_vertex_count(), mesh.components().count()),
        (6, 2)
    );
    assert!(strict("bowtie.obj").contains("non-manifold vertex"));

    let (mesh, report) = import("book.obj");
    let expected = Repairs {
        non_manifold_edges: 1,
        ..Repairs::default()
    };
    assert_eq!(report.repairs, expected);
    assert_eq!(mesh.live_face_count(), 3);
    assert_eq!(
        mesh.components().count(),
        2,
        "two pages stay glued, the third comes off"
    );
    assert!(strict("book.obj").contains("non-manifold edge"));
    assert_eq!(
        format!("repaired: {}", report.repairs),
        "repaired: 1 non-manifold edge split"
    );
}

#[test]
fn degenerate_duplicate_flipped_and_unused_are_mended_and_counted() {
    let (mesh, report) = import("untidy.obj");
    let expected = Repairs {
        degenerate_faces: 2,
        duplicate_faces: 1,
        flipped_faces: 1,
        unreferenced_vertices: 1,
        ..Repairs::default()
    };
    assert_eq!(report.repairs, expected);
    assert_eq!(mesh.live_face_count(), 3);
    // Every face now faces +z, as most of them did.
    for f in 0..mesh.face_count() {
        assert!(mesh.face_normal(f).z > 0.99, "face {f}");
    }
    assert_eq!(
        report.lines(),
        [
            "repaired: 2 degenerate faces dropped, 1 duplicate face dropped, \
          1 face flipped to match its neighbours, 1 unreferenced vertex dropped"
        ]
    );
}

#[test]
fn a_moebius_band_is_cut_open_where_no_orientation_fits() {
    let (mesh, report) = import("mobius.obj");
    assert_eq!(report.repairs.non_orientable_edges, 1);
    assert_eq!(mesh.live_face_count(), 16, "no face is lost");
    assert_eq!(mesh.components().count(), 1);
    assert!(strict("mobius.obj").contains("inconsistent orientation"));
}

#[test]
fn obj_vertex_colours_become_the_diffuse_albedo() {
    let (mesh, report) = import("coloured.obj");
    assert!(report.not_kept.is_empty(), "{:?}", report.not_kept);
    let diffuse: Vec<[f32; 3]> = mesh.brdfs().iter().map(|b| b.diffuse).collect();
    assert_eq!(
        diffuse[..3],
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    );
    assert!(
        (diffuse[3][0] - 0.214_041).abs() < 1e-5,
        "sRGB 0.5 is linear {:?}",
        diffuse[3]
    );
    assert_eq!(mesh.brdfs()[0].roughness, Brdf::CLAY.roughness);
}

#[test]
fn ply_colours_become_the_diffuse_albedo() {
    let (mesh, report) = import("colours.ply");
    assert_eq!(report.not_kept, ["vertex properties `alpha` `confidence`"]);
    let diffuse: Vec<[f32; 3]> = mesh.brdfs().iter().map(|b| b.diffuse).collect();
    // 8-bit sRGB 255 and 0 are linear 1 and 0.
    assert_eq!(
        diffuse,
        [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0]
        ]
    );
    assert!(
        mesh.brdfs()
            .iter()
            .all(|b| b.roughness == Brdf::CLAY.roughness)
    );
}

#[test]
fn another_tools_flags_are_not_our_mask() {
    // Big-endian, float colours, a quad with ushort counts, and a `flags` property with bit
    // 0x2 set on every vertex: a library's own flag, not slayer's mask.
    let (mesh, report) = import("foreign_flags_be.ply");
    assert_eq!(mesh.live_face_count(), 2);
    assert!(mesh.flags().iter().all(|f| f.is_empty()), "nothing frozen");
    assert_eq!(report.not_kept, ["vertex properties `flags`"]);
    let half = mesh.brdfs()[0].diffuse[0];
    assert!((half - 0.214_041).abs() < 1e-5, "sRGB 0.5 is linear {half}");
    assert_eq!(mesh.brdfs()[1].diffuse, [1.0, 0.0, 0.0]);
}

#[test]
fn ascii_stl_solids_become_layers_and_points_weld() {
    let (mesh, report) = import("two_solids.stl");
    assert_eq!(mesh.layer_names(), ["base_plate", "lid"]);
    assert_eq!(mesh.faces_per_layer(), [2, 1]);
    assert_eq!(
        mesh.live_vertex_count(),
        7,
        "the plate's two shared corners weld"
    );
    assert_eq!(report.welded_vertices, 2);
    assert_eq!(report.not_kept, ["3 facet normals (recomputed)"]);
}

#[test]
fn binary_stl_with_a_solid_header_is_read_as_binary() {
    let (mesh, report) = import("cad_tetra.stl");
    assert_eq!((mesh.live_vertex_count(), mesh.live_face_count()), (4, 4));
    assert_eq!(mesh.closed_components().len(), 1, "a closed tetrahedron");
    assert!(!report.repairs.any(), "{}", report.repairs);
    assert_eq!(
        report.not_kept,
        [
            "4 facet normals (recomputed)",
            "1 triangles' attribute bytes (colour)"
        ]
    );
}

#[test]
fn another_tools_gltf_keeps_its_nodes_transforms_colours_and_materials() {
    let (mesh, report) = import("two_nodes.gltf");
    assert_eq!(
        mesh.layer_names(),
        ["floor", "gem"],
        "one layer per node with a mesh"
    );
    assert_eq!(
        mesh.faces_per_layer(),
        [2, 4],
        "a strip of two, a tetrahedron"
    );
    assert_eq!(
        report.not_kept,
        ["1 texture coordinate sets", "1 normal sets (recomputed)"]
    );
    // Y-up to Z-up, through the parent's translation (0, 2, 0) in glTF's frame.
    assert_eq!(mesh.positions()[1], Vec3::new(1.0, 0.0, 2.0));
    // The gem: mirrored in x, moved by 3, then by its parent.
    assert_eq!(mesh.positions()[5], Vec3::new(2.0, 0.0, 2.0));
    // The strip faces up (+Z), and the mirrored tetrahedron still winds outward.
    assert!(mesh.face_normal(0).z > 0.99 && mesh.face_normal(1).z > 0.99);
    let gem = &mesh.closed_components()[0];
    assert!((gem.volume - 1.0 / 6.0).abs() < 1e-6, "{}", gem.volume);
    // 8-bit linear colours with no material: paint-like, clay's roughness.
    assert_eq!(mesh.brdfs()[0].diffuse, [1.0, 0.0, 0.0]);
    assert_eq!(mesh.brdfs()[3].diffuse, [1.0, 1.0, 1.0]);
    assert_eq!(mesh.brdfs()[0].roughness, Brdf::CLAY.roughness);
    // The gold metal: no diffuse, its base colour as specular, its roughness.
    let gold = mesh.brdfs()[4];
    assert_eq!(gold.diffuse, [0.0; 3]);
    assert!(close(gold.specular, [1.0, 0.8, 0.3]), "{gold:?}");
    assert!((gold.roughness - 0.3).abs() < 1e-6);
}

/// Runs the Khronos glTF validator on `files` when `tools/test.sh` installed it
/// (`SLAYER_GLTF_VALIDATOR` names its script); `None` when it is not set.
fn khronos_validator(files: &[PathBuf]) -> Option<String> {
    let script = std::env::var("SLAYER_GLTF_VALIDATOR").ok()?;
    let out = std::process::Command::new("node")
        .arg(&script)
        .args(files)
        .output()
        .unwrap_or_else(|e| panic!("SLAYER_GLTF_VALIDATOR={script}, but node did not run: {e}"));
    assert!(
        out.status.success(),
        "the validator found errors:\n{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    Some(text(&out.stdout))
}

#[test]
fn gltf_exports_are_valid_for_the_khronos_validator() {
    let dir = scratch("gltf-valid");
    let scene = dir.join("metal.ply");
    write_scene("metal", 2000, &[], &scene);
    let mut files = Vec::new();
    for ext in ["glb", "gltf"] {
        let out = dir.join(format!("metal.{ext}"));
        let done = slayer(&["convert", arg(&scene), arg(&out)]);
        assert!(done.status.success(), "{}", text(&done.stderr));
        // What our own reader checks whatever the machine has: the crate validates the
        // document, and glTF → slayer → glTF gives the same bytes.
        let (back, _) = import_mesh(&out, &ImportOptions { strict: true }).unwrap();
        let again = dir.join(format!("again.{ext}"));
        write_mesh(&back, &again).unwrap();
        assert!(
            std::fs::read(&again).unwrap() == std::fs::read(&out).unwrap(),
            "{ext}"
        );
        files.push(out);
    }
    files.push(corpus("two_nodes.gltf"));
    match khronos_validator(&files) {
        Some(report) => {
            assert_eq!(report.lines().count(), files.len(), "{report}");
            assert!(
                report.lines().all(|l| l.contains("\"errors\":0")),
                "{report}"
            );
            eprintln!("Khronos glTF validator:\n{report}");
        }
        None => eprintln!("SLAYER_GLTF_VALIDATOR not set: tools/test.sh installs the validator"),
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Two layers with their own materials, one of them painted: what an artist exports.
fn painted_scene() -> Mesh {
    let quad =
        |z: f32| [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|[x, y]| Vec3::new(x, y, z));
    let positions: Vec<Vec3> = quad(0.0).into_iter().chain(quad(0.5)).collect();
    let faces = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
    let mut mesh = Mesh::new(
        positions,
        faces,
        vec![0, 0, 1, 1],
        vec!["base".into(), "coat".into()],
    )
    .unwrap();
    mesh.set_layer_brdf(0, Brdf::new([0.7, 0.6, 0.5], [0.04; 3], 0.8));
    mesh.set_layer_brdf(1, Brdf::new([0.2, 0.3, 0.9], [0.5; 3], 0.1));
    mesh
}

#[test]
fn slayers_own_obj_comes_back_with_its_layers_and_materials() {
    let dir = std::env::temp_dir().join(format!("slayer-import-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = painted_scene();
    for name in [
        "scene.obj",
        "scene.ply",
        "scene.stl",
        "scene.glb",
        "scene.gltf",
    ] {
        let path = dir.join(name);
        write_mesh(&mesh, &path).unwrap();
        let (back, report) = import_mesh(&path, &ImportOptions { strict: true }).unwrap();
        assert_eq!(back.layer_names(), mesh.layer_names(), "{name}");
        assert_eq!(back.faces(), mesh.faces(), "{name}");
        assert_eq!(back.positions(), mesh.positions(), "{name}");
        if !name.ends_with(".stl") {
            // A roughness of 0.1 is below what `Ns` can say; `Pr` carries it exactly. STL
            // holds no material.
            assert_eq!(back.brdfs(), mesh.brdfs(), "{name}");
        }
        let welded = if name.ends_with(".stl") { 4 } else { 0 };
        let expected = ImportReport {
            welded_vertices: welded,
            ..ImportReport::default()
        };
        assert_eq!(report, expected, "{name}: nothing to say");
        // Format → slayer → the same format: the same bytes.
        // (The same name in another folder: an OBJ names its `.mtl` by file name.)
        std::fs::create_dir_all(dir.join("again")).unwrap();
        let again = dir.join("again").join(name);
        write_mesh(&back, &again).unwrap();
        let bytes = |p: &Path| std::fs::read(p).unwrap();
        assert!(
            bytes(&again) == bytes(&path),
            "{name} written again differs"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Up to `faces` triangles over `points` random points (some shared, some repeated, some
/// collinear), on up to two layers: soups as messy as a file can be.
fn soup(points: usize, faces: usize) -> impl Strategy<Value = Soup> {
    let point =
        (0u8..4, 0u8..4, 0u8..2).prop_map(|(x, y, z)| Vec3::new(x as f32, y as f32, z as f32));
    (
        prop::collection::vec(point, 3..points),
        prop::collection::vec((any::<[u32; 3]>(), 0u32..2), 1..faces),
    )
        .prop_map(|(positions, raw)| {
            let n = positions.len() as u32;
            let faces = raw.iter().map(|(f, _)| f.map(|v| v % n)).collect();
            let face_layers = raw.iter().map(|&(_, l)| l).collect();
            Soup {
                positions,
                faces,
                face_layers,
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Whatever the soup, the repair gives a mesh that builds and validates, losing only the
    /// faces it says it dropped.
    #[test]
    fn any_soup_repairs_into_a_valid_mesh(soup in soup(12, 24)) {
        let input_faces = soup.faces.len();
        let repaired = repair(soup).unwrap();
        let r = repaired.repairs;
        let kept = repaired.soup.faces.len();
        prop_assert_eq!(kept + r.degenerate_faces + r.duplicate_faces, input_faces);
        if kept == 0 {
            return Ok(());
        }
        let mesh = Mesh::new(
            repaired.soup.positions,
            repaired.soup.faces,
            repaired.soup.face_layers,
            vec!["a".into(), "b".into()],
        );
        let mesh = mesh.map_err(|e| TestCaseError::fail(format!("{e} after {r}")))?;
        prop_assert!(mesh.validate().is_ok());
    }
}

#[test]
fn the_cli_says_what_it_repaired_and_strict_refuses() {
    let dir = scratch("import-cli");
    let untidy = corpus("untidy.obj");
    let stl = dir.join("untidy.stl");
    let out = slayer(&["convert", arg(&untidy), arg(&stl)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let said = text(&out.stderr);
    assert!(
        said.contains("untidy.obj: repaired: 2 degenerate faces dropped, 1 duplicate face dropped"),
        "{said}"
    );
    assert!(text(&out.stdout).ends_with("5 vertices, 3 faces, 1 layers\n"));
    assert_one_line_error(
        &slayer(&["convert", "--strict", arg(&untidy), arg(&stl)]),
        &["untidy.obj", "degenerate"],
    );

    // `check --json` carries the repairs and what was not kept.
    let out = slayer(&["check", "--json", arg(&corpus("textured.obj"))]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(report["repairs"]["degenerate_faces"], 0);
    assert_eq!(report["not_kept"].as_array().unwrap().len(), 5);
    let out = slayer(&["check", "--json", arg(&untidy)]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(report["repairs"]["duplicate_faces"], 1);
    assert_eq!(report["repairs"]["flipped_faces"], 1);
    assert_eq!(report["valid"], true);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn convert_keeps_the_layers_asked_for_in_every_format() {
    let dir = scratch("convert");
    let scene = dir.join("bark.ply");
    write_scene("bark", 3000, &[], &scene);
    let mut digests = Vec::new();
    for ext in ["obj", "ply", "stl", "slayer"] {
        let out = dir.join(format!("inner.{ext}"));
        let done = slayer(&[
            "convert",
            arg(&scene),
            arg(&out),
            "--layers",
            "2,inner-bark",
        ]);
        assert!(done.status.success(), "{ext}: {}", text(&done.stderr));
        let check = slayer(&["check", "--json", arg(&out)]);
        let report: serde_json::Value = serde_json::from_slice(&check.stdout).expect("JSON");
        assert_eq!(report["layers"], 2, "{ext}");
        assert_eq!(report["layer_names"][1], "inner-bark", "{ext}");
        assert_eq!(report["intersections"], 0, "{ext}");
        digests.push((ext, report["faces"].clone()));
    }
    assert!(
        digests.iter().all(|(_, faces)| *faces == digests[0].1),
        "{digests:?}"
    );
    assert_one_line_error(
        &slayer(&[
            "convert",
            arg(&scene),
            arg(&dir.join("x.ply")),
            "--layers",
            "moss",
        ]),
        &["no layer `moss`", "inner-bark"],
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn the_up_axis_is_guessed_from_the_file_and_turned_exactly() {
    for (name, up) in [
        ("textured.obj", UpAxis::Y),
        ("colours.ply", UpAxis::Y),
        ("two_nodes.gltf", UpAxis::Z),
        ("cad_tetra.stl", UpAxis::Z),
    ] {
        assert_eq!(UpAxis::guess(&corpus(name)), up, "{name}");
    }
    let dir = scratch("up-axis");
    for name in ["own.obj", "own.ply"] {
        let path = dir.join(name);
        write_mesh(&painted_scene(), &path).unwrap();
        assert_eq!(UpAxis::guess(&path), UpAxis::Z, "slayer's own {name}");
    }
    std::fs::remove_dir_all(dir).unwrap();
    // Y-up: the square in the XY plane stands up in XZ, facing -Y; a quarter turn, no rounding.
    let (mut mesh, _) = import("coloured.obj");
    UpAxis::Y.to_z_up(&mut mesh);
    assert_eq!(mesh.positions()[2], Vec3::new(1.0, 0.0, 1.0));
    assert!(
        mesh.normals().iter().all(|n| (n.y + 1.0).abs() < 1e-6),
        "{:?}",
        mesh.normals()
    );
}
