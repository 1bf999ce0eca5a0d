//! Issue 22, item 3: remeshing keeps the shape of coarse closed meshes, and `check` reports the
//! shape-destroying results it can see (a closed component of fewer than 8 faces; with
//! `--against`, a closed component's volume change).

mod common;

use std::process::Command;

use glam::Vec3;
use slayer::brush::BrushKind;
use slayer::check::check_mesh;
use slayer::io::ImportReport;
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings, Remeshing};
use slayer::remesh::{RemeshSettings, VOLUME_TOLERANCE, remesh_all};
use slayer::scene::shapes;

/// The largest volume change (share) remeshing a cube at its own mean edge may make.
const CUBE_VOLUME_TOLERANCE: f64 = 0.01;

/// The unit cube, each side split into `n` × `n` squares of two triangles, wound outward.
fn cube(n: u32) -> Mesh {
    let mut positions: Vec<Vec3> = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut vertex = |p: [u32; 3]| -> u32 {
        *index.entry(p).or_insert_with(|| {
            positions.push(Vec3::from(p.map(|c| c as f32 / n as f32)));
            positions.len() as u32 - 1
        })
    };
    let mut faces = Vec::new();
    for axis in 0..3 {
        for side in [0, n] {
            let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
            for i in 0..n {
                for j in 0..n {
                    let mut corner = |a: u32, b: u32| {
                        let mut p = [0; 3];
                        (p[axis], p[u], p[w]) = (side, a, b);
                        vertex(p)
                    };
                    let q = [
                        corner(i, j),
                        corner(i + 1, j),
                        corner(i + 1, j + 1),
                        corner(i, j + 1),
                    ];
                    if side == n {
                        faces.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
                    } else {
                        faces.extend([[q[0], q[2], q[1]], [q[0], q[3], q[2]]]);
                    }
                }
            }
        }
    }
    let layers = vec![0; faces.len()];
    Mesh::new(positions, faces, layers, vec!["cube".into()]).unwrap()
}

#[test]
fn remeshing_coarse_cubes_at_their_mean_edge_keeps_their_volume() {
    for n in [1, 2, 4] {
        let mut mesh = cube(n);
        assert!(
            (common::closed_volume(&mesh) - 1.0).abs() < 1e-6,
            "a unit cube"
        );
        let faces = mesh.live_face_count();
        let edge = mesh.edge_length_stats().mean as f32;
        let report = remesh_all(&mut mesh, &RemeshSettings::new(edge)).unwrap();
        mesh.validate().unwrap();
        let volume = common::closed_volume(&mesh);
        assert!(
            (volume - 1.0).abs() <= CUBE_VOLUME_TOLERANCE,
            "{n}×{n} cube: volume {volume}, {} of {faces} faces left ({report:?})",
            mesh.live_face_count()
        );
        assert!(mesh.live_face_count() >= 12, "{n}×{n}: still a cube");
    }
}

/// A coarse cube remeshed to a much shorter edge is refined, not collapsed, and keeps its
/// volume within the remesher's bound (its creases may be chamfered within the shape
/// tolerance: measured 1.35 %).
#[test]
fn a_coarse_cube_remeshed_finer_is_refined() {
    for n in [1, 2] {
        let mut mesh = cube(n);
        let faces = mesh.live_face_count();
        let report = remesh_all(&mut mesh, &RemeshSettings::new(0.2)).unwrap();
        mesh.validate().unwrap();
        assert!(
            report.splits > 0 && mesh.live_face_count() > 4 * faces,
            "{report:?}"
        );
        let volume = common::closed_volume(&mesh);
        assert!((volume - 1.0).abs() <= VOLUME_TOLERANCE, "{volume}");
    }
}

fn smooth_dab_at_corner(remeshing: Remeshing) -> Mesh {
    let mut mesh = cube(1);
    let stroke = common::one_brush_stroke(BrushKind::Smooth, 0.12, &[Vec3::ONE]);
    Pipeline::new(PipelineSettings {
        remeshing,
        ..PipelineSettings::default()
    })
    .apply_stroke(&mut mesh, &stroke)
    .unwrap();
    mesh.validate().unwrap();
    mesh
}

/// One smooth dab at a corner of the 12-triangle cube: what the brush did stays, and the
/// remeshing after it neither folds the cube into a tetrahedron nor changes its volume.
#[test]
fn a_smooth_dab_at_a_cube_corner_keeps_the_cube() {
    let brushed = smooth_dab_at_corner(Remeshing::Off);
    let remeshed = smooth_dab_at_corner(Remeshing::AfterStroke);
    let (before, after) = (
        common::closed_volume(&brushed),
        common::closed_volume(&remeshed),
    );
    assert!(
        (after - before).abs() <= CUBE_VOLUME_TOLERANCE * before,
        "volume {before} after the dab, {after} after remeshing"
    );
    assert!(remeshed.live_face_count() >= 12);
}

#[test]
fn check_reports_a_closed_component_of_four_faces() {
    let report = check_mesh(
        &shapes::tetrahedron(),
        &ImportReport::default(),
        "tetra",
        |_| {},
    );
    assert_eq!(report.smallest_closed_faces, Some(4));
    assert!(
        report.defects.iter().any(|d| d.contains("only 4 faces")),
        "{:?}",
        report.defects
    );
    assert!(!report.is_clean());
    let octahedron = check_mesh(
        &shapes::octahedron(),
        &ImportReport::default(),
        "octa",
        |_| {},
    );
    assert!(octahedron.is_clean(), "{:?}", octahedron.defects);
}

#[test]
fn check_against_the_original_reports_a_lost_volume() {
    let dir = std::env::temp_dir().join(format!("slayer-shape-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let original = dir.join("cube.obj");
    slayer::io::write_mesh(&cube(2), &original).unwrap();
    // The cube squashed to 90 % of its height: a 10 % loss.
    let mut squashed = cube(2);
    for p in squashed.positions_mut() {
        p.z *= 0.9;
    }
    let squashed_path = dir.join("squashed.obj");
    slayer::io::write_mesh(&squashed, &squashed_path).unwrap();
    let check = |file: &std::path::Path| {
        Command::new(env!("CARGO_BIN_EXE_slayer"))
            .args(["check", "--json", "--against"])
            .arg(&original)
            .arg(file)
            .output()
            .unwrap()
    };
    let out = check(&squashed_path);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(!out.status.success(), "a 10 % loss is a defect");
    let change = json["volume_changes"][0]["change"].as_f64().unwrap();
    assert!((change + 0.1).abs() < 1e-4, "{change}");
    assert!(json["defects"][0].as_str().unwrap().contains("volume"));
    let same = check(&original);
    assert!(
        same.status.success(),
        "{}",
        String::from_utf8_lossy(&same.stdout)
    );
}

/// The distance from each vertex of `mesh` and each face's centroid to the sphere of `radius`
/// about the origin, the largest.
fn off_sphere(mesh: &Mesh, radius: f32) -> f32 {
    let centroids = (0..mesh.face_count()).map(|f| {
        let [a, b, c] = mesh.face_positions(f);
        (a + b + c) / 3.0
    });
    (mesh.positions().iter().copied())
        .chain(centroids)
        .map(|p| (p.length() - radius).abs())
        .fold(0.0, f32::max)
}

/// Refining by a large factor goes through whole subdivision levels: a sphere stays a sphere
/// (new vertices on the curve of the normals, not on the old flat faces), the result is as
/// regular as the input, and the same input gives the same output.
#[test]
fn refining_a_sphere_eightfold_keeps_it_round_and_even() {
    let start = slayer::scene::geodesic_sphere(10, 1.0).unwrap();
    let mean = start.mean_edge_length();
    let target = mean / 7.75;
    let mut mesh = start.clone();
    let report = remesh_all(&mut mesh, &RemeshSettings::new(target)).unwrap();
    assert_eq!(report.subdivisions, 3, "{report:?}");
    mesh.validate().unwrap();
    assert_eq!(slayer::collide::find_intersections(&mesh).total(), 0);
    let faces = mesh.live_face_count() as f64 / start.live_face_count() as f64;
    assert!((50.0..70.0).contains(&faces), "{faces}× the faces");
    let stats = mesh.edge_length_stats();
    assert!(stats.coefficient_of_variation() <= 0.15, "{stats:?}");
    assert!((stats.mean as f32 / target - 1.0).abs() < 0.1, "{stats:?}");
    let off = off_sphere(&mesh, 1.0);
    // The input's own faces lie up to 0.19·L (of the new L) inside the sphere: subdividing
    // them flat would leave the refined mesh that far off.
    assert!(off_sphere(&start, 1.0) > 0.15 * target);
    assert!(off <= 0.05 * target, "{:.3} L off the sphere", off / target);
    let mut again = start.clone();
    remesh_all(&mut again, &RemeshSettings::new(target)).unwrap();
    assert_eq!(again.positions(), mesh.positions());
    assert_eq!(again.faces(), mesh.faces());
}

/// A cube refined by a large factor keeps its flat sides and sharp edges: every vertex stays
/// on its surface, and the volume is the cube's.
#[test]
fn refining_a_cube_eightfold_keeps_it_a_cube() {
    let start = cube(4);
    let target = start.mean_edge_length() / 8.0;
    let mut mesh = start.clone();
    let report = remesh_all(&mut mesh, &RemeshSettings::new(target)).unwrap();
    assert!(report.subdivisions >= 2, "{report:?}");
    mesh.validate().unwrap();
    let worst = mesh
        .positions()
        .iter()
        .map(|p| {
            let q = (*p - Vec3::splat(0.5)).abs();
            (q.max_element() - 0.5).abs()
        })
        .fold(0.0, f32::max);
    assert!(worst <= 1e-4, "a vertex {worst} off the cube's sides");
    let volume = common::closed_volume(&mesh);
    assert!((volume - 1.0).abs() < 1e-3, "volume {volume}");
}
