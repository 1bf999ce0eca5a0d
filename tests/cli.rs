//! The `slayer` binary as a user runs it: exit codes, one-line errors, JSON fields.

mod common;

use common::{arg, assert_one_line_error, scratch, slayer, text, write_scene};
use std::path::Path;
use std::process::{Command, Output};

#[test]
fn scene_then_check_reports_clean_layers_as_json() {
    let dir = scratch("scene");
    let obj = dir.join("p.obj");
    write_scene("plaster", 20000, &[], &obj);
    let out = slayer(&["check", arg(&obj), "--json"]);
    assert!(out.status.success(), "{}", text(&out.stdout));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    for field in [
        "vertices",
        "faces",
        "layers",
        "components",
        "mean_edge_length",
        "edge_length_cv",
        "valid",
        "non_finite",
        "intersections",
    ] {
        assert!(report.get(field).is_some(), "missing {field}");
    }
    assert_eq!(report["layers"], 3);
    assert_eq!(report["intersections"], 0);
    assert_eq!(report["valid"], true);
    let faces = report["faces"].as_u64().unwrap();
    assert!((19_000..=21_000).contains(&faces), "{faces}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn same_scene_arguments_write_identical_files() {
    let dir = scratch("determinism");
    // Same file names in two folders: an OBJ names its material library by file name.
    for side in ["a", "b"] {
        std::fs::create_dir_all(dir.join(side)).unwrap();
    }
    for ext in ["obj", "mtl", "ply"] {
        let a = dir.join(format!("a/m.{ext}"));
        let b = dir.join(format!("b/m.{ext}"));
        if ext == "mtl" {
            // Written beside the OBJ.
            assert!(
                std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
                "{ext}"
            );
            continue;
        }
        for path in [&a, &b] {
            write_scene("bark", 6000, &["--seed", "9"], path);
        }
        assert!(
            std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
            "{ext}"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    arg(&path).to_string()
}

#[test]
fn truncated_and_corrupted_files_fail_with_one_line() {
    let dir = scratch("bad");
    let good = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    let truncated = write(&dir, "truncated.obj", &good.as_bytes()[..good.len() - 6]);
    assert_one_line_error(
        &slayer(&["check", &truncated]),
        &["truncated.obj:7", "face"],
    );

    let corrupted = write(
        &dir,
        "corrupted.obj",
        b"o a\nv 0 0 0\nv 1 0 \xff\xfe\nf 1 2 3\n",
    );
    assert_one_line_error(
        &slayer(&["check", &corrupted]),
        &["corrupted.obj:3", "not a text file"],
    );

    let garbage = write(
        &dir,
        "garbage.ply",
        &[0x70, 0x6c, 0x79, 0x0a, 0xde, 0xad, 0xbe, 0xef],
    );
    assert_one_line_error(&slayer(&["check", &garbage]), &["garbage.ply"]);

    let empty = write(&dir, "empty.obj", b"");
    assert_one_line_error(&slayer(&["check", &empty]), &["empty.obj", "no faces"]);

    let bowtie = write(
        &dir,
        "bowtie.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv -1 0 0\nv 0 -1 0\nf 1 2 3\nf 1 4 5\n",
    );
    assert_one_line_error(
        &slayer(&["check", "--strict", &bowtie]),
        &["non-manifold vertex"],
    );

    assert_one_line_error(
        &slayer(&["check", "/nonexistent/x.obj"]),
        &["/nonexistent/x.obj"],
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn defects_found_by_check_exit_non_zero() {
    let dir = scratch("defects");
    // Two sheets crossing each other.
    let crossing = write(
        &dir,
        "crossing.obj",
        b"o a\nv 0 0 0\nv 2 0 0\nv 0 2 0\no b\nv 0.5 0.5 -1\nv 0.5 0.5 1\nv 1.5 0.6 0\nf 1 2 3\nf 4 5 6\n",
    );
    let out = slayer(&["check", &crossing, "--json"]);
    assert!(!out.status.success());
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["intersections"], 1);

    let nan = write(&dir, "nan.obj", b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
    let out = slayer(&["check", &nan]);
    assert!(!out.status.success());
    assert!(
        text(&out.stdout).contains("non-finite coordinates (first at line 3)"),
        "{}",
        text(&out.stdout)
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_arguments_are_clear() {
    assert_one_line_error(
        &slayer(&["scene", "marble", "-o", "x.obj"]),
        &["unknown scene `marble`"],
    );
    assert_one_line_error(
        &slayer(&["scene", "plane", "--triangles", "5", "-o", "x.obj"]),
        &["--triangles 5 is out of range"],
    );
    assert_one_line_error(
        &slayer(&["scene", "plane", "-o", "x.dae"]),
        &["unsupported file type"],
    );
}

#[test]
fn demo_writes_and_checks_the_default_material() {
    let dir = scratch("demo");
    let out = slayer(&["demo", "--out", arg(&dir), "--triangles", "20000"]);
    assert!(
        out.status.success(),
        "{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    for file in [
        "plaster.ply",
        "strokes.json",
        "plaster-sculpted.ply",
        "plaster-sculpted.obj",
        "plaster-sculpted.mtl",
        "plaster-before.png",
        "plaster-after.png",
        "plaster-before-after.png",
    ] {
        assert!(dir.join(file).exists(), "{file}");
    }
    let stdout = text(&out.stdout);
    assert!(stdout.contains("sLayer paper, Table 1"), "{stdout}");
    assert!(stdout.contains("ok: no defects"), "{stdout}");
    // What it wrote: a sculpted mesh unlike the generated one, sound, the OBJ the same mesh,
    // and pictures with something in them.
    let before = slayer::io::read_mesh(&dir.join("plaster.ply")).unwrap();
    let after = slayer::io::read_mesh(&dir.join("plaster-sculpted.ply")).unwrap();
    assert_ne!(before.digest(), after.digest(), "the demo sculpted nothing");
    after.validate().unwrap();
    assert_eq!(slayer::collide::find_intersections(&after).total(), 0);
    let obj = slayer::io::read_mesh(&dir.join("plaster-sculpted.obj")).unwrap();
    assert_eq!(obj.live_face_count(), after.live_face_count());
    for png in ["plaster-before.png", "plaster-after.png"] {
        let image = image::open(dir.join(png)).unwrap().to_rgba8();
        let first = image.get_pixel(0, 0);
        let differing = image.pixels().filter(|p| *p != first).count();
        assert!(
            differing * 4 > image.pixels().len(),
            "{png}: {differing} pixels differ from the corner's"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn strokes_then_sculpt_round_trip_with_stats() {
    let dir = scratch("sculpt");
    let input = dir.join("in.ply");
    let strokes = dir.join("s.json");
    let output = dir.join("out.obj");
    let stats = dir.join("stats.json");
    write_scene("plaster", 20000, &[], &input);
    let out = slayer(&[
        "strokes",
        "--scene",
        "plaster",
        "--triangles",
        "20000",
        "--count",
        "3",
        "-o",
        arg(&strokes),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = slayer(&[
        "sculpt",
        "--input",
        arg(&input),
        "--strokes",
        arg(&strokes),
        // `-o`, as every command that writes a file takes it.
        "-o",
        arg(&output),
        "--stats",
        arg(&stats),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let check = slayer(&["check", arg(&output), "--json"]);
    assert!(check.status.success(), "{}", text(&check.stdout));
    let digest = |out: &Output| -> String {
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        report["digest"].as_str().unwrap().to_string()
    };
    let input_check = slayer(&["check", arg(&input), "--json"]);
    assert_ne!(
        digest(&check),
        digest(&input_check),
        "the sculpt changed nothing"
    );
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    assert_eq!(stats["strokes"].as_array().unwrap().len(), 3);
    assert!(
        stats["strokes"][0]["phases"]["collision"]
            .as_f64()
            .is_some()
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn sculpt_with_a_bad_stroke_file_fails_cleanly_and_touches_nothing() {
    let dir = scratch("bad-strokes");
    let input = dir.join("in.obj");
    write_scene("plane", 2000, &[], &input);
    let original = std::fs::read(&input).unwrap();
    let modified = std::fs::metadata(&input).unwrap().modified().unwrap();
    let cases = [
        (
            r#"{"strokes": [{"brush": "smudge", "radius": 0.1, "strength": 0.5, "layers": [0], "samples": [{"position": [0.5, 0.5, 0]}]}]}"#,
            "strokes[0].brush: the text \"smudge\" is not a brush",
        ),
        (
            r#"{"strokes": [{"brush": "draw", "radius": -0.1, "strength": 0.5, "layers": [0], "samples": [{"position": [0.5, 0.5, 0]}]}]}"#,
            "strokes[0].radius",
        ),
        (
            r#"{"strokes": [{"brush": "draw", "radius": 0.1, "strength": 0.5, "layers": [3], "samples": [{"position": [0.5, 0.5, 0]}]}]}"#,
            "layer 3 does not exist",
        ),
        (
            r#"{"strokes": [{"brush": "draw", "radius": 0.1, "layers": [0], "samples": []}]}"#,
            "strokes[0].strength: missing",
        ),
        ("not json", "s.json:1:"),
    ];
    for (content, expected) in cases {
        let strokes = write(&dir, "s.json", content.as_bytes());
        let output = dir.join("out.obj");
        let out = slayer(&[
            "sculpt",
            "--input",
            arg(&input),
            "--strokes",
            &strokes,
            "--output",
            arg(&output),
        ]);
        assert_one_line_error(&out, &[expected]);
        assert!(!output.exists(), "no output is written");
    }
    assert!(
        std::fs::read(&input).unwrap() == original,
        "the input is untouched"
    );
    assert_eq!(
        std::fs::metadata(&input).unwrap().modified().unwrap(),
        modified
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bench_writes_the_fixed_json_fields() {
    let dir = scratch("bench");
    let json = dir.join("out.json");
    let out = slayer(&[
        "bench",
        "--scene",
        "metal",
        "--triangles",
        "20000",
        "--strokes",
        "3",
        "--json",
        arg(&json),
    ]);
    assert!(
        out.status.success(),
        "{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    assert!(text(&out.stdout).contains("sLayer paper, Table 1"));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    for field in ["backend", "adapter", "threads", "revision", "scenes"] {
        assert!(report.get(field).is_some(), "missing {field}");
    }
    let scene = &report["scenes"][0];
    for field in [
        "name",
        "layers",
        "vertices",
        "faces",
        "mean_edge_length",
        "strokes",
        "samples",
        "phase_ms",
        "ms_per_sample",
        "ms_per_stroke",
        "ms_per_remesh",
        "intersections",
        "edge_band_fraction",
        "valid",
        "faces_after",
    ] {
        assert!(scene.get(field).is_some(), "missing scenes[0].{field}");
    }
    for phase in [
        "selection",
        "deformation",
        "grid_update",
        "collision",
        "remesh",
    ] {
        assert!(scene["phase_ms"][phase].as_f64().is_some(), "phase {phase}");
    }
    assert_eq!(scene["intersections"], 0);
    assert_eq!(scene["valid"], true);
    assert_eq!(scene["strokes"], 3);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Runs the binary with a private runtime folder, so that Mesa's window-system probing stays
/// quiet on headless machines and stderr holds only our own lines.
fn slayer_headless(args: &[&str]) -> Output {
    let runtime = scratch("xdg-runtime");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700)).unwrap();
    }
    Command::new(env!("CARGO_BIN_EXE_slayer"))
        .args(args)
        .env("XDG_RUNTIME_DIR", &runtime)
        .output()
        .expect("the binary runs")
}

#[test]
fn render_writes_a_png_of_the_requested_size() {
    let dir = scratch("render");
    let ply = dir.join("p.ply");
    let png = dir.join("p.png");
    write_scene("plaster", 2000, &[], &ply);
    let out = slayer_headless(&[
        "render",
        arg(&ply),
        "-o",
        arg(&png),
        "--size",
        "120×80",
        "--camera",
        "-20,60,0.8",
        "--layers",
        "0,flakes",
        "--wireframe",
        "--false-colour",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("ms"), "{}", text(&out.stdout));
    let image = slayer::render::Image::read_png(&png).unwrap();
    assert_eq!((image.width, image.height), (120, 80));
}

#[test]
fn render_of_an_empty_mesh_file_is_a_clear_error() {
    // The readers refuse a mesh with no faces; the library renders such a mesh as a blank
    // image (tests/render.rs), which `render` would announce with a warning.
    let dir = scratch("render-empty");
    let ply = dir.join("empty.ply");
    let png = dir.join("empty.png");
    std::fs::write(
        &ply,
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n\
         property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
    )
    .unwrap();
    let out = slayer_headless(&["render", arg(&ply), "-o", arg(&png)]);
    assert_one_line_error(&out, &["empty.ply", "no faces"]);
    assert!(!png.exists());
}

#[test]
fn render_mistakes_are_one_line_errors() {
    let dir = scratch("render-errors");
    let ply = dir.join("p.ply");
    write_scene("plane", 200, &[], &ply);
    let png = dir.join("x.png");
    let (ply, png) = (arg(&ply), arg(&png));
    let missing = dir.join("missing.ply");
    assert_one_line_error(
        &slayer_headless(&["render", arg(&missing), "-o", png]),
        &["missing.ply"],
    );
    assert_one_line_error(
        &slayer_headless(&["render", ply, "-o", png, "--size", "99999x10"]),
        &["too large"],
    );
    assert_one_line_error(
        &slayer_headless(&["render", ply, "-o", png, "--layers", "7"]),
        &["--layers", "no layer `7`"],
    );
    assert_one_line_error(
        &slayer_headless(&["render", ply, "-o", arg(&dir.join("x.jpg"))]),
        &[".png"],
    );
    // Clap rejects malformed values before anything runs.
    for (flag, value) in [
        ("--size", "0x10"),
        ("--size", "wide"),
        ("--camera", "1,2,3,4"),
    ] {
        let out = slayer_headless(&["render", ply, "-o", png, flag, value]);
        assert!(!out.status.success(), "{flag} {value}");
        assert!(text(&out.stderr).contains(value), "{}", text(&out.stderr));
    }
}

/// Issue 4's check as a user runs it: a deliberately irregular scene, remeshed, comes back
/// with uniform edges (cv < 0.15) and passes `slayer check`.
#[test]
fn remesh_makes_a_jittered_scene_uniform_and_clean() {
    let dir = scratch("remesh");
    let (rough, smooth) = (dir.join("rough.ply"), dir.join("smooth.ply"));
    write_scene("plaster", 8000, &["--jitter", "0.4"], &rough);
    let cv = |path: &Path| {
        let out = slayer(&["check", arg(path), "--json"]);
        assert!(out.status.success(), "{}", text(&out.stdout));
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        assert_eq!(report["intersections"], 0);
        report["edge_length_cv"].as_f64().unwrap()
    };
    let before = cv(&rough);
    assert!(before > 0.2, "the jittered scene is irregular: cv {before}");
    let out = slayer(&["remesh", arg(&rough), "-o", arg(&smooth)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("smallest angle"));
    let after = cv(&smooth);
    assert!(after < 0.15, "cv {before} -> {after}");
    assert_one_line_error(
        &slayer(&["scene", "plaster", "--jitter", "0.9", "-o", arg(&rough)]),
        &["--jitter"],
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// `remesh --faces N` lands near N faces, `--scale F` multiplies the edge by F (refining a
/// sphere eightfold through subdivision), and `--json` reports the quality before and after
/// and the distance to the input; conflicting or absurd targets are one-line errors.
#[test]
fn remesh_to_a_face_count_or_a_scale_reports_its_quality() {
    let dir = scratch("remesh-targets");
    let (sphere, out_file) = (dir.join("sphere.ply"), dir.join("out.ply"));
    write_scene("sphere", 2000, &[], &sphere);
    let remesh = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec!["remesh", arg(&sphere), "-o", arg(&out_file), "--json"];
        args.extend_from_slice(extra);
        let out = slayer(&args);
        assert!(out.status.success(), "{extra:?}: {}", text(&out.stderr));
        serde_json::from_slice(&out.stdout).expect("JSON")
    };
    let report = remesh(&["--faces", "8000"]);
    let faces = report["after"]["faces"].as_f64().unwrap();
    assert!((faces / 8000.0 - 1.0).abs() < 0.1, "{faces} faces for 8000");
    let report = remesh(&["--scale", "0.125"]);
    assert_eq!(report["remesh"]["subdivisions"], 3);
    let ratio =
        report["after"]["faces"].as_f64().unwrap() / report["before"]["faces"].as_f64().unwrap();
    assert!((50.0..75.0).contains(&ratio), "{ratio}× the faces");
    assert!(report["after"]["edge_cv"].as_f64().unwrap() <= 0.15);
    assert!(report["after"]["smallest_angle"]["p1"].as_f64().unwrap() >= 30.0);
    assert!(report["after"]["valence_6"].as_f64().unwrap() > 0.8);
    // Refined on the curve of the normals, the result lies off the input's flat faces by
    // their own distance to the sphere (0.19 of the new edge here; tests/shape.rs measures
    // the distance to the sphere itself), nowhere farther.
    let distance = &report["distance_to_input"];
    assert!(distance["max"].as_f64().unwrap() < 0.25, "{distance}");
    assert!(distance["samples"].as_u64().unwrap() > 100_000);
    // Remeshed at its own resolution, the result stays on the input's faces.
    let same = remesh(&[]);
    let distance = &same["distance_to_input"];
    assert!(distance["max"].as_f64().unwrap() < 0.1, "{distance}");
    assert_eq!(same["remesh"]["subdivisions"], 0);
    let lines = slayer(&[
        "remesh",
        arg(&sphere),
        "-o",
        arg(&out_file),
        "--scale",
        "0.5",
    ]);
    let shown = text(&lines.stdout);
    assert!(
        shown.contains("valence of interior vertices") && shown.contains("distance to the input"),
        "{shown}"
    );
    let both = slayer(&[
        "remesh",
        arg(&sphere),
        "-o",
        arg(&out_file),
        "--edge",
        "0.01",
        "--faces",
        "100",
    ]);
    assert!(!both.status.success());
    assert!(
        text(&both.stderr).contains("cannot be used with"),
        "{}",
        text(&both.stderr)
    );
    for (args, expected) in [
        (vec!["--scale=-2"], "--scale -2 is not a positive factor"),
        (vec!["--faces", "0"], "--faces 0"),
        (vec!["--scale", "0.0001"], "the limit is"),
    ] {
        let mut all = vec!["remesh", arg(&sphere), "-o", arg(&out_file)];
        all.extend(args);
        assert_one_line_error(&slayer(&all), &[expected]);
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// A missing file is named once, with the system's reason once.
#[test]
fn a_missing_file_is_one_plain_line() {
    let out = slayer(&["check", "/nonexistent/slayer-missing.ply"]);
    assert_one_line_error(&out, &["slayer-missing.ply"]);
    let stderr = text(&out.stderr);
    assert_eq!(stderr.matches("os error").count(), 1, "{stderr}");
}

/// `--backend both` runs the same strokes on the CPU and with the GPU's kernels (lavapipe here)
/// and writes docs/bench.md's `parity` object; an unknown backend is a one-line error.
#[test]
fn bench_on_both_backends_writes_parity() {
    let dir = scratch("bench-both");
    let json = dir.join("out.json");
    let out = slayer_headless(&[
        "bench",
        "--scene",
        "plaster",
        "--triangles",
        "4000",
        "--strokes",
        "2",
        "--backend",
        "both",
        "--json",
        arg(&json),
    ]);
    assert!(
        out.status.success(),
        "{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(report["backend"], "both");
    let parity = &report["parity"];
    let edges = parity["max_position_deviation_edges"]
        .as_f64()
        .expect("same topology");
    assert!(edges <= 1e-4, "{edges}");
    assert_eq!(parity["collision_count_cpu"], parity["collision_count_gpu"]);
    assert!(
        parity["collision_count_cpu"].as_u64().unwrap() > 0,
        "the strokes never collided: {parity}"
    );
    for field in ["max_position_deviation", "gpu_over_cpu"] {
        assert!(parity.get(field).is_some(), "missing parity.{field}");
    }
    assert_eq!(report["gpu_scenes"][0]["intersections"], 0);
    // GPU memory: the allocator's figures (wgpu's Vulkan backend keeps them) hold at least the
    // positions (12 bytes a vertex) and no more than it reserved; the CPU run holds none.
    let memory = &report["gpu_scenes"][0]["gpu_memory"];
    let vertices = report["gpu_scenes"][0]["vertices"].as_u64().unwrap();
    if report["adapter"].as_str().unwrap().contains("Vulkan") {
        let allocated = memory["allocated_bytes"]
            .as_u64()
            .expect("an allocator report");
        let reserved = memory["reserved_bytes"]
            .as_u64()
            .expect("an allocator report");
        assert!(
            allocated >= 12 * vertices && allocated <= reserved,
            "{memory}"
        );
    }
    assert!(
        memory["budget_bytes"].as_u64().unwrap() >= 12 * vertices,
        "{memory}"
    );
    assert!(report["scenes"][0]["gpu_memory"].is_null());
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("gpu memory plaster (gpu): at most"),
        "{stdout}"
    );
    let out = slayer(&["bench", "--scene", "plaster", "--backend", "quantum"]);
    assert!(!out.status.success());
    let first = text(&out.stderr)
        .lines()
        .next()
        .unwrap_or_default()
        .to_string();
    assert!(first.contains("unknown backend `quantum`"), "{first}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// `--backend` and `--remesh` from the command line: the GPU's kernels (lavapipe here) give the
/// CPU's result, remeshing after every sample changes the topology where `off` keeps it, and
/// `adapters` names the adapter the GPU runs used.
#[test]
fn sculpt_backends_and_remesh_modes_from_the_command_line() {
    let dir = scratch("sculpt-modes");
    let (input, strokes) = (dir.join("in.ply"), dir.join("s.json"));
    write_scene("plaster", 3000, &[], &input);
    let out = slayer(&[
        "strokes",
        "--scene",
        "plaster",
        "--triangles",
        "3000",
        "--count",
        "2",
        "-o",
        arg(&strokes),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let sculpt = |backend: &str, remesh: &str| {
        let output = dir.join(format!("{backend}-{remesh}.ply"));
        let out = slayer_headless(&[
            "sculpt",
            "--input",
            arg(&input),
            "--strokes",
            arg(&strokes),
            "--output",
            arg(&output),
            "--backend",
            backend,
            "--remesh",
            remesh,
        ]);
        assert!(
            out.status.success(),
            "{backend} {remesh}: {}",
            text(&out.stderr)
        );
        slayer::io::read_mesh(&output).unwrap()
    };
    let start = slayer::io::read_mesh(&input).unwrap();
    let (cpu, gpu) = (sculpt("cpu", "off"), sculpt("gpu", "off"));
    assert_ne!(cpu.digest(), start.digest(), "the strokes changed nothing");
    assert_eq!(cpu.faces(), start.faces(), "remeshing off keeps the faces");
    let deviation = cpu
        .positions()
        .iter()
        .zip(gpu.positions())
        .map(|(p, q)| p.distance(*q))
        .fold(0.0f32, f32::max);
    assert!(deviation <= 1e-4 * start.mean_edge_length(), "{deviation}");
    let remeshed = sculpt("cpu", "sample");
    assert_ne!(
        remeshed.faces(),
        start.faces(),
        "remeshing per sample edits the faces"
    );
    remeshed.validate().unwrap();
    assert_eq!(slayer::collide::find_intersections(&remeshed).total(), 0);
    let adapters = slayer_headless(&["adapters", "--json"]);
    assert!(adapters.status.success(), "{}", text(&adapters.stderr));
    let listed: serde_json::Value = serde_json::from_slice(&adapters.stdout).unwrap();
    assert!(listed.as_array().is_some_and(|a| !a.is_empty()), "{listed}");
    std::fs::remove_dir_all(dir).unwrap();
}
