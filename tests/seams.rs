//! Issue 22, item 5: a surface split into OBJ groups becomes one layer per group, and the
//! faces meeting along the seam share vertex positions without crossing. `check` must call
//! such a file clean, and still count groups that truly cross.

use std::fmt::Write;
use std::path::PathBuf;
use std::process::Command;

use slayer::collide::find_intersections;
use slayer::io::{Format, read_mesh_bytes};

/// A geodesic sphere as OBJ text, its faces in group `top` (centroid above z = 0) or `bottom`,
/// all of them on one shared vertex list: the seam's vertices belong to both groups.
fn sphere_in_two_groups(extra_bottom: &str) -> String {
    let sphere = slayer::scene::geodesic_sphere(3, 1.0).unwrap();
    let mut obj = String::new();
    for p in sphere.positions() {
        writeln!(obj, "v {} {} {}", p.x, p.y, p.z).unwrap();
    }
    let (mut top, mut bottom) = (String::new(), String::new());
    for f in 0..sphere.face_count() {
        let [a, b, c] = sphere.faces()[f];
        let centroid = sphere.face_positions(f).iter().map(|p| p.z).sum::<f32>();
        let line = format!("f {} {} {}\n", a + 1, b + 1, c + 1);
        if centroid > 0.0 {
            top.push_str(&line);
        } else {
            bottom.push_str(&line);
        }
    }
    format!("{obj}{extra_bottom}g top\n{top}g bottom\n{bottom}")
}

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("slayer-seams-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn check_json(path: &std::path::Path) -> (bool, serde_json::Value) {
    let out = Command::new(env!("CARGO_BIN_EXE_slayer"))
        .args(["check", "--json", path.to_str().unwrap()])
        .output()
        .unwrap();
    let json = serde_json::from_slice(&out.stdout).expect("check prints JSON");
    (out.status.success(), json)
}

#[test]
fn groups_meeting_along_a_seam_are_not_intersecting() {
    let text = sphere_in_two_groups("");
    let mesh = read_mesh_bytes(text.as_bytes(), Format::Obj, "seam.obj").unwrap();
    assert_eq!(mesh.layer_count(), 2, "one layer per group");
    let report = find_intersections(&mesh);
    assert_eq!(report.total(), 0, "{report:?}");

    let (clean, json) = check_json(&write("seam.obj", &text));
    assert_eq!(json["intersections"], 0, "{json}");
    assert!(clean, "check exits 0 on a seam: {}", json["defects"]);
}

#[test]
fn groups_that_truly_cross_are_still_counted() {
    // A triangle in the bottom group, reaching from inside the sphere out through the top
    // group: it shares no position with the top, and crosses it.
    let spike = "v 0.1 0.05 0.2\nv -0.1 0.05 0.2\nv 0 -0.05 1.6\n";
    let mut text = sphere_in_two_groups(spike);
    let n = slayer::scene::geodesic_sphere(3, 1.0)
        .unwrap()
        .positions()
        .len();
    writeln!(text, "f {} {} {}", n + 1, n + 2, n + 3).unwrap();
    let mesh = read_mesh_bytes(text.as_bytes(), Format::Obj, "crossing.obj").unwrap();
    let report = find_intersections(&mesh);
    assert!(report.between_layers > 0, "{report:?}");

    let (clean, json) = check_json(&write("crossing.obj", &text));
    assert!(json["intersections_between_layers"].as_u64().unwrap() > 0);
    assert!(!clean, "check exits non-zero on a true crossing");
}
