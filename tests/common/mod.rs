//! What the tests share: running the `slayer` binary, scratch folders, scenes written with it,
//! the check of a one-line error, and a stroke of one brush built in code.

// Each test crate uses the part it needs.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the binary with `args` and waits for it.
pub fn slayer(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_slayer"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// An empty folder for one test, under the system's temporary folder.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("slayer-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Output bytes as text.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A path as a command-line argument.
pub fn arg(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Writes `scene` with about `triangles` triangles to `path` (`slayer scene`, with `extra`
/// options before `-o`), which must succeed: the input most tests start from.
pub fn write_scene(scene: &str, triangles: u32, extra: &[&str], path: &Path) {
    let triangles = triangles.to_string();
    let mut args = vec!["scene", scene, "--triangles", &triangles];
    args.extend_from_slice(extra);
    args.extend(["-o", arg(path)]);
    let out = slayer(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

/// The command failed with exactly one line on stderr, `error: …`, holding each of
/// `must_contain`, and no panic.
pub fn assert_one_line_error(output: &Output, must_contain: &[&str]) {
    assert!(!output.status.success(), "expected failure");
    let stderr = text(&output.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "one line: {stderr}");
    assert!(lines[0].starts_with("error: "), "{stderr}");
    for s in must_contain {
        assert!(lines[0].contains(s), "`{s}` missing in: {stderr}");
    }
}

/// A stroke of `kind` at full strength on layer 0 through `samples` (full pressure), with the
/// default falloff and spacing: what tests of one brush build in code.
pub fn one_brush_stroke(
    kind: slayer::brush::BrushKind,
    radius: f32,
    samples: &[glam::Vec3],
) -> slayer::brush::Stroke {
    use slayer::brush::{Brush, Falloff, Sample, Stroke};
    Stroke {
        brush: Brush {
            kind,
            radius,
            strength: 1.0,
            falloff: Falloff::default(),
            invert: false,
        },
        paint: None,
        layers: vec![0],
        spacing: 0.25,
        symmetry: None,
        samples: samples
            .iter()
            .map(|&position| Sample {
                position,
                pressure: 1.0,
                normal: None,
            })
            .collect(),
    }
}

/// Two triangles on edge whose edges cross where no vertex comes near the other's face: the
/// case vertex–triangle proximity cannot see, left to the exact backstop. Layer 0 stands
/// upright in the plane x = 0 with its lower edge along y at height `0.3·h`; layer 1 stands in
/// the plane y = 0 with its upper edge along x at height 0. Returns the mesh and a grab (layer
/// 0, radius 2.5·h) that drags layer 0 down by 0.8·h: its lower edge would pass through layer
/// 1's upper edge while every vertex stays more than 0.5·h from the other triangle.
pub fn crossing_edges(h: f32) -> (slayer::mesh::Mesh, slayer::brush::Stroke) {
    use glam::Vec3;
    let z = 0.3 * h;
    let positions = vec![
        Vec3::new(0.0, -h, z),
        Vec3::new(0.0, h, z),
        Vec3::new(0.0, 0.0, z + h),
        Vec3::new(-h, 0.0, 0.0),
        Vec3::new(h, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -h),
    ];
    let mesh = slayer::mesh::Mesh::new(
        positions,
        vec![[0, 1, 2], [3, 4, 5]],
        vec![0, 1],
        vec!["blade".into(), "wall".into()],
    )
    .expect("two triangles");
    let grab_at = Vec3::new(0.0, 0.0, z + 0.5 * h);
    let stroke = one_brush_stroke(
        slayer::brush::BrushKind::Grab,
        2.5 * h,
        &[grab_at, grab_at - Vec3::Z * (0.8 * h)],
    );
    (mesh, stroke)
}

/// `mesh` (a plane, say) with every vertex moved by `shape`, given its position in the unit
/// square of the mesh's x and y extent: the folded, ridged and grooved sheets of the culling
/// tests.
pub fn reshaped(
    mut mesh: slayer::mesh::Mesh,
    shape: impl Fn(f32, f32) -> glam::Vec3,
) -> slayer::mesh::Mesh {
    let (lo, hi) = mesh.bounds().unwrap();
    let size = hi - lo;
    for p in mesh.positions_mut() {
        let (u, v) = ((p.x - lo.x) / size.x, (p.y - lo.y) / size.y);
        *p = shape(u, v);
    }
    mesh.recompute_normals();
    mesh
}

/// Points from `from` to `to`, `count` of them, ends included: a stroke's path.
pub fn line(from: glam::Vec3, to: glam::Vec3, count: usize) -> Vec<glam::Vec3> {
    (0..count)
        .map(|i| from.lerp(to, i as f32 / (count - 1) as f32))
        .collect()
}

/// Two sheets 3 apart (20×20 quads of edge 1, layers 0 and 1) and a grab of radius 4 caught at
/// the upper sheet's middle, pushed 5 down onto the lower sheet (collisions hold it there) and
/// pulled back up to where it began: a grab outside any fuse layer whose vertices collisions hold
/// still, so it lets go of them and takes them back when the drag turns.
pub fn grab_pushed_into_a_layer_and_back() -> (slayer::mesh::Mesh, slayer::brush::Stroke) {
    use glam::Vec3;
    let mesh = slayer::scene::shapes::stacked_sheets(2, 20, 20, 1.0, 3.0);
    let middle = Vec3::new(10.0, 10.0, 3.0);
    let down = middle - Vec3::Z * 5.0;
    let path: Vec<Vec3> = line(middle, down, 11)
        .into_iter()
        .chain(line(down, middle, 11).into_iter().skip(1))
        .collect();
    let mut stroke = one_brush_stroke(slayer::brush::BrushKind::Grab, 4.0, &path);
    stroke.layers = vec![1];
    (mesh, stroke)
}

/// How far the upper sheet of [`grab_pushed_into_a_layer_and_back`] is left below where it
/// began (z = 3), summed over its vertices.
pub fn upper_sheet_sunk(mesh: &slayer::mesh::Mesh) -> f32 {
    (mesh.positions().iter().zip(mesh.vertex_layers()))
        .filter(|&(_, &layer)| layer == 1)
        .map(|(p, _)| (3.0 - p.z).max(0.0))
        .sum()
}

/// The volume `mesh` encloses, which must be one closed component.
pub fn closed_volume(mesh: &slayer::mesh::Mesh) -> f64 {
    let closed = mesh.closed_components();
    assert_eq!(closed.len(), 1, "one closed component");
    closed[0].volume
}

/// A torus about z: `around` quads the long way, `across` the short way, each split in two.
pub fn torus(around: u32, across: u32, (major, minor): (f32, f32)) -> slayer::mesh::Mesh {
    use std::f32::consts::TAU;
    let mut positions = Vec::new();
    for i in 0..around {
        let u = TAU * i as f32 / around as f32;
        for j in 0..across {
            let v = TAU * j as f32 / across as f32;
            let ring = major + minor * v.cos();
            positions.push(glam::Vec3::new(
                ring * u.cos(),
                ring * u.sin(),
                minor * v.sin(),
            ));
        }
    }
    let at = |i: u32, j: u32| (i % around) * across + j % across;
    let mut faces = Vec::new();
    for i in 0..around {
        for j in 0..across {
            faces.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            faces.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let layers = vec![0; faces.len()];
    slayer::mesh::Mesh::new(positions, faces, layers, vec!["ring".into()]).expect("torus")
}
