//! Symmetric sculpting: on a mesh mirrored across x = 0, strokes mirrored across x keep it
//! mirrored, both sides colliding with each other in the same steps; through the library and
//! through `slayer sculpt --symmetry x`.
//!
//! Selection, brush frames, deformation, vertex normals (summed order-free) and the proximity
//! clamp (closest points from canonically ordered corners) are mirror-exact, so the measured
//! asymmetry is 0; the bound asserted is the issue's, [`TOLERANCE`]. Remeshing is off: its edits
//! follow vertex order, which a mirror does not keep.

use glam::Vec3;
use slayer::bench::{BrushMix, ScriptSpec, generate_script};
use slayer::brush::{StrokeFile, SymmetrySpec};
use slayer::collide::find_intersections;
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings, Remeshing};
use slayer::scene::{SceneKind, SceneSpec, generate};

/// The asymmetry one mirrored stroke may leave, in edge lengths (the issue asks 1e-5; see the
/// module's comment for what stands between).
const TOLERANCE: f32 = 1e-5;

/// A plaster scene moved to x > `gap` and its mirror image across x = 0 beside it, in one
/// mesh: vertex `i` of the first half mirrors vertex `i + n` of the second.
fn mirrored_plaster(faces: usize, gap_edges: f32) -> (Mesh, usize) {
    let half = generate(&SceneSpec {
        kind: SceneKind::Plaster,
        triangles: faces,
        seed: 4,
    })
    .unwrap();
    let (lo, _) = half.bounds().unwrap();
    let shift = Vec3::new(gap_edges * half.mean_edge_length() - lo.x, 0.0, 0.0);
    let n = half.vertex_count();
    let mut positions: Vec<Vec3> = half.positions().iter().map(|&p| p + shift).collect();
    let images: Vec<Vec3> = positions
        .iter()
        .map(|p| Vec3::new(-p.x, p.y, p.z))
        .collect();
    positions.extend(images);
    let mut faces = half.faces().to_vec();
    // A reflection turns orientation inside out: reversed windings keep the normals outward.
    faces.extend(
        half.faces()
            .iter()
            .map(|&[a, b, c]| [a + n as u32, c + n as u32, b + n as u32]),
    );
    let mut face_layers = half.face_layers().to_vec();
    face_layers.extend_from_slice(half.face_layers());
    let mesh = Mesh::new(positions, faces, face_layers, half.layer_names().to_vec()).unwrap();
    (mesh, n)
}

/// Strokes of every brush over the mirrored scene, from `seed`.
fn strokes(mesh: &Mesh, seed: u64) -> StrokeFile {
    generate_script(
        mesh,
        &ScriptSpec {
            strokes: 8,
            seed,
            samples: 10,
            mix: BrushMix::Torture,
            ..ScriptSpec::default()
        },
    )
}

/// The largest distance between a vertex of the first half and the image of its twin.
fn asymmetry(mesh: &Mesh, n: usize) -> f32 {
    let p = mesh.positions();
    (0..n)
        .map(|i| {
            let image = p[i + n] * Vec3::new(-1.0, 1.0, 1.0);
            p[i].distance(image)
        })
        .fold(0.0, f32::max)
}

/// Every brush of the torture mix, one mirrored stroke each from the mirrored scene.
#[test]
fn mirrored_strokes_keep_a_mirrored_mesh_mirrored() {
    let (input, n) = mirrored_plaster(3_000, 1.5);
    let edge = input.mean_edge_length();
    assert_eq!(asymmetry(&input, n), 0.0);
    let mut file = strokes(&input, 21);
    for stroke in &mut file.strokes {
        stroke.symmetry = Some(SymmetrySpec::Axis("x".into()));
        stroke.radius *= 2.0;
    }
    let mut clamped = 0;
    for stroke in &file.resolve(&input, "script").unwrap() {
        let mut mesh = input.clone();
        let mut pipeline = Pipeline::new(PipelineSettings {
            remeshing: Remeshing::Off,
            ..PipelineSettings::default()
        });
        clamped += pipeline.apply_stroke(&mut mesh, stroke).unwrap().clamped;
        let moved: Vec<usize> = (0..mesh.vertex_count())
            .filter(|&v| mesh.positions()[v] != input.positions()[v])
            .collect();
        // Both halves moved alike: the image dabs ran.
        let images = moved.iter().filter(|&&v| v >= n).count();
        assert_eq!(images * 2, moved.len(), "{:?}", stroke.brush.kind);
        let worst = asymmetry(&mesh, n) / edge;
        assert!(
            worst <= TOLERANCE,
            "{:?}: asymmetry {worst:e} L",
            stroke.brush.kind
        );
        assert_eq!(find_intersections(&mesh).total(), 0);
        mesh.validate().unwrap();
    }
    assert!(clamped > 0, "nothing collided");
}

/// A stroke drawn across the mirror plane presses both halves into each other: they collide in
/// the same steps, and nothing crosses.
#[test]
fn the_two_sides_collide_with_each_other() {
    let (mut mesh, n) = mirrored_plaster(3_000, 1.0);
    let edge = mesh.mean_edge_length();
    let (lo, hi) = mesh.bounds().unwrap();
    // Grab the first half's inner rim toward the plane and past it: its image comes the other
    // way, into it.
    let y = (lo.y + hi.y) * 0.5;
    let z = hi.z;
    let text = format!(
        r#"{{"strokes": [{{"brush": "grab", "radius": {r}, "strength": 1.0, "layers": [0, 1, 2],
            "symmetry": "x", "samples": [{{"position": [{x0}, {y}, {z}]}}, {{"position": [{x1}, {y}, {z}]}}]}}]}}"#,
        r = 6.0 * edge,
        x0 = 2.0 * edge,
        x1 = -4.0 * edge,
    );
    let file = StrokeFile::parse(&text, "grab.json").unwrap();
    let resolved = file.resolve(&mesh, "grab.json").unwrap();
    let mut pipeline = Pipeline::new(PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    });
    let report = pipeline.apply_stroke(&mut mesh, &resolved[0]).unwrap();
    assert!(report.clamped > 0, "the halves never met");
    assert_eq!(find_intersections(&mesh).total(), 0);
    assert_eq!(asymmetry(&mesh, n), 0.0, "a grab's clamp is mirror-exact");
    // No vertex of the first half passed the plane: its image holds it back.
    let crossed = (0..n).filter(|&v| mesh.positions()[v].x < 0.0).count();
    assert_eq!(crossed, 0);
}

#[test]
fn cli_sculpt_with_symmetry_x_gives_a_mirrored_result() {
    let dir = std::env::temp_dir().join(format!("slayer-symmetry-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (mesh, n) = mirrored_plaster(2_000, 1.5);
    let edge = mesh.mean_edge_length();
    let (input, script, output) = (dir.join("m.ply"), dir.join("s.json"), dir.join("o.ply"));
    slayer::io::write_mesh(&mesh, &input).unwrap();
    std::fs::write(&script, serde_json::to_string(&strokes(&mesh, 5)).unwrap()).unwrap();
    let path = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_slayer"))
        .args([
            "sculpt",
            "--input",
            &path(&input),
            "--strokes",
            &path(&script),
        ])
        .args([
            "--output",
            &path(&output),
            "--symmetry",
            "x",
            "--remesh",
            "off",
        ])
        .args(["--backend", "cpu"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let sculpted = slayer::io::read_mesh(&output).unwrap();
    assert_ne!(sculpted.digest(), mesh.digest());
    let worst = asymmetry(&sculpted, n) / edge;
    assert!(worst <= TOLERANCE, "asymmetry {worst:e} L");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Strokes of every brush in a row, each on the last one's result, with clamps and the exact
/// backstop's reverts on both sides: the mesh stays mirrored after every one.
#[test]
fn a_sequence_of_mirrored_strokes_stays_mirrored() {
    let (mut mesh, n) = mirrored_plaster(2_000, 1.5);
    let edge = mesh.mean_edge_length();
    let mut file = strokes(&mesh, 5);
    file.strokes.extend(strokes(&mesh, 9).strokes);
    for stroke in &mut file.strokes {
        stroke.symmetry = Some(SymmetrySpec::Axis("x".into()));
    }
    let mut pipeline = Pipeline::new(PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    });
    let (mut clamped, mut reverted) = (0, 0);
    for stroke in &file.resolve(&mesh, "script").unwrap() {
        let report = pipeline.apply_stroke(&mut mesh, stroke).unwrap();
        (clamped, reverted) = (clamped + report.clamped, reverted + report.reverted);
        let worst = asymmetry(&mesh, n) / edge;
        assert!(
            worst <= TOLERANCE,
            "{:?}: asymmetry {worst:e} L",
            stroke.brush.kind
        );
    }
    assert!(
        clamped > 0 && reverted > 0,
        "clamped {clamped}, reverted {reverted}"
    );
    assert_eq!(find_intersections(&mesh).total(), 0);
}
