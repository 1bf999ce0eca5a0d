//! Mesh files: round trips and every malformed case with its message (`tests/fuzz.rs` mangles
//! thousands more).

use glam::Vec3;
use slayer::io::{Format, ImportOptions, encode_mesh, import_bytes, read_mesh_bytes};
use slayer::mesh::{Brdf, Mesh, VertexFlags};
use slayer::scene::{SceneKind, SceneSpec, generate, shapes};

fn small_scene() -> Mesh {
    let mesh = generate(&SceneSpec {
        kind: SceneKind::Plaster,
        triangles: 5_000,
        seed: 4,
    })
    .unwrap();
    assert!(mesh.faces_per_layer().iter().all(|&f| f > 0));
    mesh
}

fn read(text: &str) -> Result<Mesh, String> {
    read_mesh_bytes(text.as_bytes(), Format::Obj, "t.obj").map_err(|e| e.to_string())
}

#[test]
fn obj_round_trip_keeps_positions_faces_and_layers() {
    let mesh = small_scene();
    let bytes = encode_mesh(&mesh, Format::Obj);
    let back = read_mesh_bytes(&bytes, Format::Obj, "p.obj").unwrap();
    assert!(
        back.positions() == mesh.positions(),
        "positions are written exactly, in order"
    );
    assert!(back.faces() == mesh.faces());
    assert_eq!(back.face_layers(), mesh.face_layers());
    assert_eq!(back.layer_names(), mesh.layer_names());
    // And the second trip writes the same bytes.
    assert!(encode_mesh(&back, Format::Obj) == bytes);
}

#[test]
fn ply_round_trip_keeps_brdfs_layers_and_masks() {
    let mut mesh = small_scene();
    mesh.brdfs_mut()[5] = Brdf::new([0.1, 0.2, 0.3], [0.4, 0.5, 0.6], 0.77);
    mesh.flags_mut()[9].insert(VertexFlags::MASKED);
    mesh.flags_mut()[10].insert(VertexFlags::LOCKED);
    let bytes = encode_mesh(&mesh, Format::Ply);
    let back = read_mesh_bytes(&bytes, Format::Ply, "p.ply").unwrap();
    assert!(back.positions() == mesh.positions());
    assert!(back.faces() == mesh.faces());
    assert!(back.brdfs() == mesh.brdfs());
    assert!(back.vertex_layers() == mesh.vertex_layers());
    assert_eq!(back.layer_names(), mesh.layer_names());
    assert!(back.flags()[9].contains(VertexFlags::MASKED));
    assert!(
        !back.flags()[10].contains(VertexFlags::LOCKED),
        "locks are per stroke, not saved"
    );
}

#[test]
fn ply_keeps_which_layers_fuse() {
    let mesh = small_scene();
    assert!(mesh.layer_count() >= 2);
    let mut bytes = Vec::new();
    slayer::io::write_ply_with(&mesh, &[1], &mut bytes).unwrap();
    let options = ImportOptions::default();
    let (_, report) = import_bytes(&bytes, Format::Ply, "p.ply", &options).unwrap();
    assert_eq!(report.fuse_layers, vec![1]);
    assert!(report.lines().is_empty(), "a policy is not a repair");
    // A mark for a layer the file does not have is dropped; other formats keep none.
    let line = b"comment slayer fuse 1\n";
    let at = bytes.windows(line.len()).position(|w| w == line).unwrap() + line.len();
    let mut marked = bytes[..at].to_vec();
    marked.extend_from_slice(b"comment slayer fuse 99\n");
    marked.extend_from_slice(&bytes[at..]);
    let (_, report) = import_bytes(&marked, Format::Ply, "p.ply", &options).unwrap();
    assert_eq!(report.fuse_layers, vec![1]);
    let plain = encode_mesh(&mesh, Format::Ply);
    let (_, report) = import_bytes(&plain, Format::Ply, "p.ply", &options).unwrap();
    assert!(report.fuse_layers.is_empty());
}

#[test]
fn ascii_ply_with_quads_and_extra_properties() {
    let text = "ply\nformat ascii 1.0\ncomment hand made\nelement vertex 7\nproperty double x\n\
                property double y\nproperty double z\nproperty uchar red\nelement face 2\n\
                property list uchar int vertex_indices\nproperty int layer\nelement edge 1\n\
                property int a\nproperty int b\nend_header\n0 0 0 255\n1 0 0 0\n1 1 0 0\n0 1 0 0\n\
                9 9 9 0\n9 8 9 0\n8 9 9 0\n4 0 1 2 3 0\n3 4 4 4 1\n0 1\n";
    // The second face repeats a vertex: dropped, with its three vertices, or under strict an
    // error naming the face.
    let lenient = ImportOptions::default();
    let (mesh, report) = import_bytes(text.as_bytes(), Format::Ply, "q.ply", &lenient).unwrap();
    assert_eq!(mesh.live_face_count(), 2, "a quad becomes two triangles");
    assert_eq!(report.repairs.degenerate_faces, 1);
    assert_eq!(report.repairs.unreferenced_vertices, 3);
    let strict = ImportOptions { strict: true };
    let e = import_bytes(text.as_bytes(), Format::Ply, "q.ply", &strict)
        .unwrap_err()
        .to_string();
    assert!(e.contains("face") && e.contains("repeats"), "{e}");
    // Another tool's `layer` is not ours: one layer, and the property listed as not kept.
    let fixed = text.replace("3 4 4 4 1", "3 4 5 6 1");
    let (mesh, report) = import_bytes(fixed.as_bytes(), Format::Ply, "q.ply", &lenient).unwrap();
    assert_eq!(mesh.live_face_count(), 3);
    assert_eq!(mesh.layer_count(), 1);
    assert_eq!(
        report.not_kept,
        ["face properties `layer`", "1 `edge` rows"],
        "{report:?}"
    );
    // The same file said to be slayer's: its `layer` is read.
    let ours = fixed.replace("comment hand made", "comment written by slayer");
    let mesh = read_mesh_bytes(ours.as_bytes(), Format::Ply, "q.ply").unwrap();
    assert_eq!(mesh.layer_count(), 2);
}

#[test]
fn obj_objects_and_groups_become_layers_and_duplicates_weld() {
    let text = "# two layers\no bottom\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n\
                g top\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 5 6 7\nf 8 9 10\n";
    let mesh = read(text).unwrap();
    assert_eq!(mesh.layer_names(), ["bottom", "top"]);
    assert_eq!(mesh.faces_per_layer(), vec![2, 2]);
    assert_eq!(
        mesh.live_vertex_count(),
        8,
        "the top layer's repeated corners weld"
    );
    assert_eq!(mesh.components().count(), 2);
}

#[test]
fn obj_polygons_are_triangulated_and_negative_indices_work() {
    let mesh = read("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\nf -5 -4 -3 -2 -1\n").unwrap();
    assert_eq!(mesh.live_face_count(), 3);
}

#[test]
fn malformed_obj_names_file_line_and_problem() {
    let cases: [(&str, &str); 12] = [
        (
            "v 0 0 0\nv 1 0\n",
            "t.obj:2: vertex needs three coordinates",
        ),
        (
            "v 0 0 0\nv 1 x 0\n",
            "t.obj:2: vertex coordinate 1 is not a number",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            "t.obj:4: face vertex index 4 is out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n",
            "t.obj:4: face vertex index 0 is out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 2 3\n",
            "t.obj:4: face vertex index -4 is out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
            "t.obj:4: face has 2 corners",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 a\n",
            "t.obj:4: face vertex index `a` is not an integer",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n",
            "t.obj:4: face texture index 1 is out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n",
            "t.obj:3: 1 vertices have a non-finite coordinate",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 1e30 1 0\nf 1 2 3\n",
            "t.obj:3: vertex coordinate beyond the supported range",
        ),
        ("# nothing here\n", "t.obj: no faces"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 0 0\nf 1 2 3\n",
            "t.obj: no faces left after the repair (1 degenerate face dropped",
        ),
    ];
    for (text, expected) in cases {
        let e = read(text).unwrap_err();
        assert!(
            e.contains(expected),
            "{text:?}\n  got:      {e}\n  expected: {expected}"
        );
        assert!(!e.contains('\n'), "one line: {e}");
    }
}

#[test]
fn non_manifold_obj_under_strict_names_the_edge_and_where_it_is() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n";
    let strict = ImportOptions { strict: true };
    let e = import_bytes(text.as_bytes(), Format::Obj, "t.obj", &strict)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("non-manifold edge") && e.contains("at (0, 0, 0)"),
        "{e}"
    );
}

#[test]
fn malformed_ply_is_reported() {
    let cases: [(&[u8], &str); 6] = [
        (b"ply\nformat ascii 1.0\nelement vertex 1\n", "header ends before `end_header`"),
        (b"plx\n", "not a PLY file"),
        (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n0\n0\n0\n", "no `y` property"),
        (
            b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0",
            "the header's element counts need at least 48000000000 bytes, but the file holds 2",
        ),
        (
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n",
            "vertex index 9 is out of range",
        ),
        (
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -2\n",
            "is not a valid index",
        ),
    ];
    for (bytes, expected) in cases {
        let e = read_mesh_bytes(bytes, Format::Ply, "t.ply")
            .unwrap_err()
            .to_string();
        assert!(e.contains(expected), "got: {e}\nexpected: {expected}");
    }
}

#[test]
fn writing_is_atomic_and_reports_unwritable_paths() {
    let dir = std::env::temp_dir().join(format!("slayer-io-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("m.ply");
    let mesh = shapes::octahedron();
    slayer::io::write_mesh(&mesh, &path).unwrap();
    let back = slayer::io::read_mesh(&path).unwrap();
    assert_eq!(back.positions(), mesh.positions());
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .collect();
    assert_eq!(leftovers.len(), 1, "no temporary file is left behind");
    let e = slayer::io::write_mesh(&mesh, &dir.join("missing/m.obj")).unwrap_err();
    assert!(e.to_string().contains("missing/m.obj"));
    let e = slayer::io::write_mesh(&mesh, &dir.join("m.dae")).unwrap_err();
    assert!(e.to_string().contains("unsupported"));
    std::fs::remove_dir_all(&dir).unwrap();
    let _ = Vec3::ZERO;
}

#[test]
fn obj_files_come_with_a_material_library_per_layer_and_still_read_back() {
    let dir = std::env::temp_dir().join(format!("slayer-io-mtl-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = slayer::scene::generate(&slayer::scene::SceneSpec {
        triangles: 2000,
        ..slayer::scene::SceneSpec::new(slayer::scene::SceneKind::Plaster)
    })
    .unwrap();
    let path = dir.join("plaster.obj");
    slayer::io::write_mesh(&mesh, &path).unwrap();
    let obj = std::fs::read_to_string(&path).unwrap();
    assert!(obj.contains("mtllib plaster.mtl\n"), "{}", &obj[..200]);
    assert_eq!(obj.matches("usemtl ").count(), 3);
    let mtl = std::fs::read_to_string(dir.join("plaster.mtl")).unwrap();
    assert_eq!(mtl.matches("newmtl ").count(), 3);
    for (name, preset) in [
        ("plaster", slayer::material::PLASTER),
        ("paint", slayer::material::PAINT),
        ("flakes", slayer::material::PEELING_PAINT),
    ] {
        let block = mtl.split(&format!("newmtl {name}\n")).nth(1).unwrap();
        let [r, g, b] = preset.brdf.diffuse;
        assert!(
            block.contains(&format!("# preset {}", preset.name)),
            "{block}"
        );
        assert!(block.contains(&format!("Kd {r} {g} {b}\n")), "{block}");
        let ns = slayer::mesh::blinn_exponent(preset.brdf.roughness);
        assert!(block.contains(&format!("Ns {ns}\n")), "{block}");
    }
    // Our reader (tobj underneath) keeps one layer per object and ignores the library.
    let back = slayer::io::read_mesh(&path).unwrap();
    assert_eq!(back.layer_names(), mesh.layer_names());
    assert_eq!(back.positions(), mesh.positions());
    assert_eq!(back.faces(), mesh.faces());
    std::fs::remove_dir_all(&dir).unwrap();
}
