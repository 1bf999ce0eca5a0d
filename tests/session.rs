//! The editing session: every stroke one history entry; undo restores the mesh bit for bit and
//! redo the sculpted one; a new stroke after an undo drops the redo branch; the memory cap drops
//! the oldest entries; the session file keeps all of it and refuses damaged files.

use proptest::prelude::*;
use slayer::bench::{BrushMix, ScriptSpec, generate_script};
use slayer::collide::find_intersections;
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings};
use slayer::scene::{SceneKind, SceneSpec, generate};
use slayer::session::{Session, read_session, write_session};

fn scene(kind: SceneKind, faces: usize) -> Mesh {
    generate(&SceneSpec {
        kind,
        triangles: faces,
        seed: 5,
    })
    .unwrap()
}

/// The torture strokes' brush radius in mean edges: two thirds of the bench's 12, which
/// grows the scenes about threefold over 200 strokes (to 57K and 67K faces) where 12 grew bark
/// past 160K, each late stroke then costing seconds. The property does not depend on the size.
const RADIUS_EDGES: f32 = 8.0;

/// `count` strokes of every brush, pushed hard (the torture mix), from `seed`, of `samples`
/// samples each.
fn torture_strokes(
    mesh: &Mesh,
    (count, samples): (usize, usize),
    seed: u64,
) -> Vec<slayer::brush::Stroke> {
    let spec = ScriptSpec {
        strokes: count,
        seed,
        samples,
        radius_edges: RADIUS_EDGES,
        mix: BrushMix::Torture,
        ..ScriptSpec::default()
    };
    generate_script(mesh, &spec)
        .resolve(mesh, "script")
        .unwrap()
}

/// Every array of the two meshes, compared by bits (dead rows and adjacency included).
fn assert_bit_identical(a: &Mesh, b: &Mesh, what: &str) {
    let bits = |values: &[glam::Vec3]| -> Vec<[u32; 3]> {
        values
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(
        bits(a.positions()),
        bits(b.positions()),
        "{what}: positions"
    );
    assert_eq!(bits(a.normals()), bits(b.normals()), "{what}: normals");
    let brdf_bits = |m: &Mesh| -> Vec<[u32; 7]> {
        m.brdfs()
            .iter()
            .map(|b| b.as_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(brdf_bits(a), brdf_bits(b), "{what}: BRDFs");
    assert_eq!(a.flags(), b.flags(), "{what}: flags");
    assert_eq!(
        a.vertex_layers(),
        b.vertex_layers(),
        "{what}: vertex layers"
    );
    assert_eq!(a.faces(), b.faces(), "{what}: faces");
    assert_eq!(a.face_layers(), b.face_layers(), "{what}: face layers");
    assert_eq!(a.adjacency(), b.adjacency(), "{what}: adjacency");
    assert_eq!(a.layer_names(), b.layer_names(), "{what}: layer names");
    assert_eq!(a.digest(), b.digest(), "{what}: digest");
}

/// 200 strokes of every brush with remeshing on, then undo all and redo all.
fn undo_all_and_redo_all(kind: SceneKind) {
    let input = scene(kind, 20_000);
    let strokes = torture_strokes(&input, (200, 4), 11);
    let mut session = Session::new(input.clone());
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    let mut changed = 0;
    for stroke in &strokes {
        let (_, recorded) = session.apply_stroke(&mut pipeline, stroke).unwrap();
        changed += recorded.changed as usize;
        assert_eq!(recorded.dropped, 0);
    }
    assert!(
        changed > 150,
        "{kind:?}: only {changed} of 200 strokes changed the mesh"
    );
    assert_eq!(session.history().entries().len(), 200);
    let sculpted = session.mesh().clone();
    eprintln!(
        "{kind:?}: {} faces -> {} after 200 strokes",
        input.face_count(),
        sculpted.face_count()
    );
    assert_ne!(sculpted.digest(), input.digest());
    assert!(
        sculpted.face_count() != input.face_count(),
        "{kind:?}: remeshing never ran"
    );

    while session.undo().is_some() {}
    assert_bit_identical(
        session.mesh(),
        &input,
        &format!("{kind:?} after undoing all"),
    );
    // The pipeline's grid follows the mesh back: a stroke now sculpts as on the input.
    let mut fresh = input.clone();
    Pipeline::new(PipelineSettings::default())
        .apply_stroke(&mut fresh, &strokes[0])
        .unwrap();
    let mut replay = session.clone();
    replay.apply_stroke(&mut pipeline, &strokes[0]).unwrap();
    assert_bit_identical(
        replay.mesh(),
        &fresh,
        &format!("{kind:?} stroke after undo"),
    );

    while session.redo().is_some() {}
    assert_bit_identical(
        session.mesh(),
        &sculpted,
        &format!("{kind:?} after redoing all"),
    );
    session.mesh().validate().unwrap();
}

#[test]
fn plaster_undo_all_and_redo_all_are_bit_exact() {
    undo_all_and_redo_all(SceneKind::Plaster);
}

#[test]
fn bark_undo_all_and_redo_all_are_bit_exact() {
    undo_all_and_redo_all(SceneKind::Bark);
}

#[derive(Debug, Clone, Copy)]
enum Op {
    Stroke(usize),
    Undo,
    Redo,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        3 => (0usize..1000).prop_map(Op::Stroke),
        2 => Just(Op::Undo),
        1 => Just(Op::Redo),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4, ..ProptestConfig::default() })]

    /// Random interleavings of strokes, undos and redos: the mesh stays valid with no crossing
    /// at every step, a stroke after an undo drops the redo branch, and undoing everything
    /// returns the input.
    #[test]
    fn interleaved_undo_redo_and_strokes_keep_the_mesh_sound(
        ops in prop::collection::vec(op(), 24),
        seed in 0u64..1000,
    ) {
        let input = scene(SceneKind::Plaster, 4_000);
        let strokes = torture_strokes(&input, (12, 8), seed);
        let mut session = Session::new(input.clone());
        let mut pipeline = Pipeline::new(PipelineSettings::default());
        for op in ops {
            match op {
                Op::Stroke(i) => {
                    session.apply_stroke(&mut pipeline, &strokes[i % strokes.len()]).unwrap();
                    prop_assert!(!session.history().can_redo());
                }
                Op::Undo => { session.undo(); }
                Op::Redo => { session.redo(); }
            }
            session.mesh().validate().unwrap();
            prop_assert_eq!(find_intersections(session.mesh()).total(), 0);
        }
        while session.undo().is_some() {}
        assert_bit_identical(session.mesh(), &input, "after undoing all");
    }
}

/// A session without history (what `sculpt` uses for a mesh output) sculpts the same mesh as
/// one with history, records nothing and has nothing to undo; a session whose history is
/// dropped part-way lets go of what it held.
#[test]
fn a_session_without_history_sculpts_the_same_and_records_nothing() {
    let mesh = scene(SceneKind::Plaster, 3_000);
    let strokes = torture_strokes(&mesh, (3, 6), 9);
    let mut with = Session::new(mesh.clone());
    let mut without = Session::without_history(mesh);
    assert!(with.keeps_history() && !without.keeps_history());
    for stroke in &strokes {
        let mut pipeline = Pipeline::new(PipelineSettings::default());
        let (_, recorded) = with.apply_stroke(&mut pipeline, stroke).unwrap();
        assert!(recorded.bytes > 0);
        let mut pipeline = Pipeline::new(PipelineSettings::default());
        let (_, recorded) = without.apply_stroke(&mut pipeline, stroke).unwrap();
        assert_eq!((recorded.bytes, recorded.dropped), (0, 0));
    }
    assert_eq!(with.mesh().digest(), without.mesh().digest());
    assert!(without.history().entries().is_empty());
    assert!(without.undo().is_none());
    with.drop_history();
    assert!(with.history().entries().is_empty());
    assert!(with.undo().is_none());
}

#[test]
fn the_memory_cap_drops_the_oldest_entries_and_says_so() {
    let input = scene(SceneKind::Plaster, 4_000);
    let strokes = torture_strokes(&input, (16, 8), 3);
    let mut session = Session::new(input);
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    let mut sizes = Vec::new();
    for stroke in &strokes[..4] {
        sizes.push(session.apply_stroke(&mut pipeline, stroke).unwrap().1.bytes);
    }
    let cap = sizes.iter().sum::<usize>();
    assert_eq!(session.set_history_cap(cap), 0);
    let mut dropped = 0;
    for stroke in &strokes[4..] {
        dropped += session
            .apply_stroke(&mut pipeline, stroke)
            .unwrap()
            .1
            .dropped;
        // Under the cap, or one entry larger than the cap on its own, kept alone.
        let history = session.history();
        assert!(history.bytes() <= cap || history.entries().len() == 1);
    }
    assert!(dropped > 0, "no entry was dropped");
    assert_eq!(session.history().dropped(), dropped);
    // What is left undoes to the mesh as the oldest kept entry found it, a valid one.
    let kept = session.history().entries().len();
    let mut undone = 0;
    while session.undo().is_some() {
        undone += 1;
    }
    assert_eq!(undone, kept);
    session.mesh().validate().unwrap();
}

#[test]
fn the_session_file_keeps_the_mesh_the_layers_and_the_history() {
    let input = scene(SceneKind::Bark, 3_000);
    let strokes = torture_strokes(&input, (6, 8), 8);
    let mut session = Session::new(input.clone());
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    for stroke in &strokes {
        session.apply_stroke(&mut pipeline, stroke).unwrap();
    }
    session.rename_layer(1, "moss").unwrap();
    let mut hidden = session.layers()[0];
    hidden.visible = false;
    session.set_layer(0, hidden).unwrap();
    session.undo();

    let bytes = write_session(&session, true);
    let mut read = read_session(&bytes, "test.slayer").unwrap();
    assert_bit_identical(read.mesh(), session.mesh(), "read back");
    assert_eq!(read.layers(), session.layers());
    assert_eq!(read.brush, session.brush);
    assert_eq!(read.history(), session.history());
    // The history goes on where it was: redo, then undo everything back to the input.
    read.redo().unwrap();
    assert!(!read.layers()[0].visible);
    while read.undo().is_some() {}
    assert_bit_identical(read.mesh(), &input, "read back, undone");

    let without = read_session(&write_session(&session, false), "t.slayer").unwrap();
    assert!(without.history().entries().is_empty());
    assert_eq!(without.mesh().digest(), session.mesh().digest());
}

#[test]
fn damaged_session_files_are_refused_with_one_line() {
    let session = Session::new(scene(SceneKind::Plaster, 2_000));
    let bytes = write_session(&session, true);
    let error = |bytes: &[u8]| read_session(bytes, "s.slayer").unwrap_err().to_string();

    let mut wrong_magic = bytes.clone();
    wrong_magic[1] = b'X';
    assert!(error(&wrong_magic).contains("not a slayer session file"));
    let mut newer = bytes.clone();
    newer[8..12].copy_from_slice(&2u32.to_le_bytes());
    assert!(error(&newer).contains("version 2"), "{}", error(&newer));
    // A flipped byte in every section's body is caught by that section's checksum.
    for at in [40, bytes.len() / 2, bytes.len() - 3] {
        let mut flipped = bytes.clone();
        flipped[at] ^= 0x10;
        let message = error(&flipped);
        assert!(message.contains("checksum"), "byte {at}: {message}");
    }
    for cut in [5, 13, 30, bytes.len() / 3, bytes.len() - 1] {
        let message = error(&bytes[..cut]);
        assert!(
            !message.contains('\n') && message.starts_with("s.slayer"),
            "{message}"
        );
    }
}

#[test]
fn the_digest_is_the_same_through_ply_and_the_session_file() {
    let input = scene(SceneKind::Metal, 3_000);
    let strokes = torture_strokes(&input, (4, 8), 2);
    let mut session = Session::new(input);
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    for stroke in &strokes {
        session.apply_stroke(&mut pipeline, stroke).unwrap();
    }
    let mesh = session.mesh();
    assert!(
        (0..mesh.face_count()).any(|f| mesh.is_face_dead(f)),
        "remeshing left no dead rows to skip"
    );
    let ply = slayer::io::encode_mesh(mesh, slayer::io::Format::Ply);
    let from_ply = slayer::io::read_mesh_bytes(&ply, slayer::io::Format::Ply, "t.ply").unwrap();
    assert_eq!(from_ply.digest(), mesh.digest());
    let from_session = read_session(&write_session(&session, false), "t.slayer").unwrap();
    assert_eq!(from_session.mesh().digest(), mesh.digest());
    // Any change of content changes it.
    let mut moved = from_ply.clone();
    moved.positions_mut()[0].x += 1e-6;
    assert_ne!(moved.digest(), mesh.digest());
}

/// The `slayer` binary, run as a user runs it.
fn slayer(args: &[&str]) -> std::process::Output {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_slayer"))
        .args(args)
        .output()
        .expect("the binary runs");
    assert!(
        !String::from_utf8_lossy(&out.stderr).contains("panicked"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn digest_of(path: &std::path::Path) -> String {
    let out = slayer(&["check", "--json", path.to_str().unwrap()]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    report["digest"].as_str().expect("a digest").to_string()
}

/// The headless round trip: a scene as a session, sculpted with a stroke file into a session
/// that keeps every stroke, undone stroke by stroke back to the scene's digest.
#[test]
fn cli_sculpt_then_undo_every_stroke_gives_the_scene_back() {
    let dir = std::env::temp_dir().join(format!("slayer-session-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = |name: &str| dir.join(name);
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (scene, strokes) = (path("b.slayer"), path("s.json"));
    let (sculpted, undone) = (path("s.slayer"), path("u.slayer"));
    for args in [
        vec!["scene", "bark", "--triangles", "4000", "-o", &s(&scene)],
        vec![
            "strokes",
            "--scene",
            "bark",
            "--triangles",
            "4000",
            "--count",
            "6",
            "-o",
            &s(&strokes),
        ],
        vec![
            "sculpt",
            "--input",
            &s(&scene),
            "--strokes",
            &s(&strokes),
            "--output",
            &s(&sculpted),
            "--backend",
            "cpu",
        ],
    ] {
        let out = slayer(&args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert_ne!(digest_of(&sculpted), digest_of(&scene));

    let out = slayer(&["history", "--json", &s(&sculpted)]);
    let history: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(history["entries"].as_array().unwrap().len(), 6);
    assert_eq!(history["done"], 6);

    let out = slayer(&["undo", &s(&sculpted), "--steps", "6", "-o", &s(&undone)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(digest_of(&undone), digest_of(&scene));
    let redone = path("r.slayer");
    let out = slayer(&["redo", &s(&undone), "--steps", "6", "-o", &s(&redone)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(digest_of(&redone), digest_of(&sculpted));
    // The undone entries are kept for redo; one more undo than there are is refused.
    let out = slayer(&["undo", &s(&undone), "-o", &s(&path("x.slayer"))]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("more than the 0 entries"));
    // A mesh has no history to undo.
    let ply = path("b.ply");
    assert!(
        slayer(&["scene", "plane", "--triangles", "200", "-o", &s(&ply)])
            .status
            .success()
    );
    let out = slayer(&["undo", &s(&ply), "-o", &s(&path("y.ply"))]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("only a session file"));
}
