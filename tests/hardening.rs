//! Issue 22, item 4 (and item 1 as a user meets it): the promises the CLI makes hold against
//! hostile inputs — the input is never overwritten by accident, closed pipes end quietly,
//! `--json` is always JSON, multi-file outputs change as one, temporary files do not pile up,
//! file bytes never drive the terminal, special files are refused before they are read, and
//! stroke-file mistakes are told in our words.

mod common;

use common::{arg, assert_one_line_error, scratch, slayer, text, write_scene};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs the binary, failing the test (not hanging it) if it runs longer than `limit`.
fn slayer_within(args: &[&str], limit: Duration) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_slayer"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let started = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("`slayer {}` ran past {limit:?}", args.join(" "));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// The files in `dir`, sorted by name.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn stroke_file(dir: &Path, name: &str, stroke: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, format!(r#"{{"strokes": [{stroke}]}}"#)).unwrap();
    path
}

const SMALL_STROKE: &str = r#"{"brush": "draw", "radius": 0.1, "strength": 0.5, "layers": [0],
    "samples": [{"position": [0.5, 0.5, 0]}, {"position": [0.6, 0.5, 0]}]}"#;

#[test]
fn sculpt_refuses_to_overwrite_its_input_without_in_place() {
    let dir = scratch("in-place");
    let input = dir.join("a.obj");
    write_scene("plane", 2000, &[], &input);
    let strokes = stroke_file(&dir, "s.json", SMALL_STROKE);
    let original = std::fs::read(&input).unwrap();
    let linked = dir.join("b.obj");
    std::fs::hard_link(&input, &linked).unwrap();
    let spelled = dir.join(".").join("a.obj");
    for output in [&input, &linked, &spelled] {
        let out = slayer(&[
            "sculpt",
            "--input",
            arg(&input),
            "--strokes",
            arg(&strokes),
            "--output",
            arg(output),
        ]);
        assert_one_line_error(&out, &["the output is the input file", "--in-place"]);
        assert!(std::fs::read(&input).unwrap() == original, "{output:?}");
    }
    let out = slayer(&[
        "sculpt",
        "--input",
        arg(&input),
        "--strokes",
        arg(&strokes),
        "--output",
        arg(&input),
        "--in-place",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        std::fs::read(&input).unwrap() != original,
        "sculpted in place"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// Stdout closed before the command prints: the command ends quietly (the conventional
/// SIGPIPE death or success), never with a panic's exit status 101.
#[test]
fn a_closed_stdout_ends_quietly() {
    let dir = scratch("pipe");
    let mesh = dir.join("p.obj");
    write_scene("plane", 500, &[], &mesh);
    let remeshed = dir.join("r.obj");
    let commands: [&[&str]; 4] = [
        &["check", arg(&mesh)],
        &["check", arg(&mesh), "--json"],
        &["remesh", arg(&mesh), "-o", arg(&remeshed)],
        &["adapters"],
    ];
    for args in commands {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader); // every write to stdout now fails
        let out = Command::new(env!("CARGO_BIN_EXE_slayer"))
            .args(args)
            .env("XDG_RUNTIME_DIR", &dir)
            .stdout(writer)
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let stderr = text(&out.stderr);
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert_ne!(out.status.code(), Some(101), "{args:?}: {stderr}");
        #[cfg(unix)]
        {
            use std::os::unix::process::ExitStatusExt;
            assert!(
                out.status.success() || out.status.signal() == Some(libc::SIGPIPE),
                "{args:?}: {:?} {stderr}",
                out.status
            );
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn check_json_prints_json_when_loading_fails() {
    let dir = scratch("json-error");
    let malformed = dir.join("bad.obj");
    std::fs::write(&malformed, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 zebra\n").unwrap();
    let missing = dir.join("missing.obj");
    for (path, expected) in [(&malformed, "zebra"), (&missing, "missing.obj")] {
        let out = slayer(&["check", arg(path), "--json"]);
        assert!(!out.status.success());
        let report: serde_json::Value = serde_json::from_slice(&out.stdout)
            .unwrap_or_else(|e| panic!("not JSON ({e}): {}", text(&out.stdout)));
        let error = report["error"].as_str().expect("an `error` string");
        assert!(error.contains(expected), "{error}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// An OBJ and its `.mtl`, or an output and its stats, change together or not at all: a write
/// that fails part-way leaves every old file byte-identical and no temporary file behind.
#[test]
fn a_failing_write_leaves_every_old_file_intact() {
    let dir = scratch("all-or-nothing");
    let (obj, mtl) = (dir.join("out.obj"), dir.join("out.mtl"));
    write_scene("plane", 500, &[], &obj);
    let (old_obj, old_mtl) = (std::fs::read(&obj).unwrap(), std::fs::read(&mtl).unwrap());
    let before = listing(&dir);

    // The stats path is a folder: its rename fails after the mesh's could have succeeded.
    let stats = dir.join("stats");
    std::fs::create_dir(&stats).unwrap();
    let input = dir.join("in.ply");
    write_scene("plane", 2000, &[], &input);
    let strokes = stroke_file(&dir, "s.json", SMALL_STROKE);
    let out = slayer(&[
        "sculpt",
        "--input",
        arg(&input),
        "--strokes",
        arg(&strokes),
        "--output",
        arg(&obj),
        "--stats",
        arg(&stats),
        "--backend",
        "cpu",
    ]);
    assert_one_line_error(&out, &["stats"]);
    assert!(
        std::fs::read(&obj).unwrap() == old_obj,
        "the OBJ is the old one"
    );
    assert!(
        std::fs::read(&mtl).unwrap() == old_mtl,
        "the .mtl is the old one"
    );

    // The `.mtl` path is a folder: the OBJ must not change without it.
    std::fs::remove_file(&mtl).unwrap();
    std::fs::create_dir(&mtl).unwrap();
    let out = slayer(&["scene", "plane", "--triangles", "900", "-o", arg(&obj)]);
    assert!(!out.status.success());
    assert!(
        std::fs::read(&obj).unwrap() == old_obj,
        "the OBJ is the old one"
    );
    let mut expected = before.clone();
    expected.extend(["in.ply".to_string(), "s.json".into(), "stats".into()]);
    expected.sort();
    assert_eq!(listing(&dir), expected, "no temporary file is left");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Temporary files a killed run left (`.NAME.slayer-tmp.PID` of a dead process) are removed by
/// the next write into that folder; a live process's, and files of other patterns, are not.
#[test]
fn stale_temporary_files_are_swept() {
    let dir = scratch("sweep");
    // Above Linux's largest process id: no such process can be running.
    let stale = dir.join(".out.obj.slayer-tmp.999999999");
    let live = dir.join(format!(".out.obj.slayer-tmp.{}", std::process::id()));
    let other = dir.join(".out.obj.tmp12345");
    for path in [&stale, &live, &other] {
        std::fs::write(path, b"left behind").unwrap();
    }
    write_scene("plane", 500, &[], &dir.join("out.obj"));
    assert!(!stale.exists(), "a dead process's temporary file is swept");
    assert!(live.exists(), "a live process's is kept");
    assert!(other.exists(), "files of other patterns are not ours");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Bytes quoted from a file (a face index, a PLY header line, a layer name in a stroke file)
/// reach the message escaped: no escape sequence reaches the terminal.
#[test]
fn file_bytes_in_messages_are_escaped() {
    let dir = scratch("escape");
    let obj = dir.join("evil.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \x1b]0;owned\x07\n").unwrap();
    let ply = dir.join("evil.ply");
    std::fs::write(&ply, "ply\nformat ascii 1.0\n\x1b[2J\x1b[31m\nend_header\n").unwrap();
    let input = dir.join("in.obj");
    write_scene("plane", 2000, &[], &input);
    let strokes = stroke_file(
        &dir,
        "s.json",
        r#"{"brush": "draw", "radius": 0.1, "strength": 0.5, "layers": ["\u001b[2Jx"],
            "samples": [{"position": [0.5, 0.5, 0]}]}"#,
    );
    let output = dir.join("out.obj");
    let runs = [
        slayer(&["check", arg(&obj)]),
        slayer(&["check", arg(&ply)]),
        slayer(&[
            "sculpt",
            "--input",
            arg(&input),
            "--strokes",
            arg(&strokes),
            "--output",
            arg(&output),
        ]),
    ];
    for out in runs {
        assert!(!out.status.success());
        let stderr = text(&out.stderr);
        assert!(!stderr.contains('\x1b'), "raw escape: {stderr:?}");
        assert!(!stderr.contains('\x07'), "raw bell: {stderr:?}");
        assert!(stderr.contains("\\u{1b}"), "escaped: {stderr:?}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// A FIFO, a folder and a link to `/dev/zero` are refused before they are read (a FIFO must
/// not block); a file over the size bound is refused before a byte of it is read.
#[cfg(unix)]
#[test]
fn special_and_oversized_files_are_refused_before_reading() {
    let dir = scratch("special");
    let fifo = dir.join("fifo.obj");
    let status = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(status.success());
    let zero = dir.join("zero.obj");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let folder = dir.join("folder.ply");
    std::fs::create_dir(&folder).unwrap();
    // Sparse: takes no disk, but its length is over the 4 GiB bound.
    let huge = dir.join("huge.obj");
    let file = std::fs::File::create(&huge).unwrap();
    file.set_len(slayer::files::MAX_INPUT_BYTES + 1).unwrap();
    let limit = Duration::from_secs(20);
    for (path, expected) in [
        (&fifo, "a FIFO"),
        (&zero, "a character device"),
        (&folder, "a folder"),
        (&huge, "larger than 4.0 GiB"),
    ] {
        let out = slayer_within(&["check", arg(path)], limit);
        assert_one_line_error(&out, &[arg(path), expected]);
    }
    // A stroke file and a stencil given as FIFOs.
    let input = dir.join("in.obj");
    write_scene("plane", 2000, &[], &input);
    let fifo_json = dir.join("fifo.json");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo_json)
            .status()
            .unwrap()
            .success()
    );
    let output = dir.join("out.obj");
    let sculpt = |strokes: &Path| {
        slayer_within(
            &[
                "sculpt",
                "--input",
                arg(&input),
                "--strokes",
                arg(strokes),
                "--output",
                arg(&output),
            ],
            limit,
        )
    };
    assert_one_line_error(&sculpt(&fifo_json), &["fifo.json", "a FIFO"]);
    let stencil = stroke_file(
        &dir,
        "stencil.json",
        &format!(
            r#"{{"brush": "paint", "radius": 0.1, "strength": 0.5, "layers": [0],
            "paint": {{"material": "rust", "stencil": {{"png": "{}", "tile": 0.1}}}},
            "samples": [{{"position": [0.5, 0.5, 0]}}]}}"#,
            arg(&fifo)
        ),
    );
    assert_one_line_error(&sculpt(&stencil), &["paint.stencil.png", "a FIFO"]);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Stroke-file mistakes name the field and what it allows, in our words: never the parser's
/// (`untagged enum`, `expected value`, `invalid type`, `variant`).
#[test]
fn stroke_file_mistakes_are_told_in_our_words() {
    let dir = scratch("our-words");
    let input = dir.join("in.obj");
    write_scene("plane", 2000, &[], &input);
    let output = dir.join("out.obj");
    let sample = r#""samples": [{"position": [0.5, 0.5, 0]}]"#;
    let cases = [
        (
            format!(r#""brush": 5, "radius": 0.1, "strength": 0.5, "layers": [0], {sample}"#),
            "strokes[0].brush: the number 5 is not a brush (brushes: draw,",
        ),
        (
            format!(r#""brush": "draw", "radius": 0.1, "strength": 0.5, "layers": [true], {sample}"#),
            "strokes[0].layers[0]: `true` is not a layer (give its index",
        ),
        (
            format!(r#""brush": "draw", "radius": 0.1, "strength": 0.5, "layers": [-1], {sample}"#),
            "strokes[0].layers[0]: -1 is not a layer index",
        ),
        (
            format!(r#""brush": "draw", "radius": "big", "strength": 0.5, "layers": [0], {sample}"#),
            "strokes[0].radius: the text \"big\" is not a number",
        ),
        (
            format!(r#""brush": "draw", "radius": 0.1, "strength": 0.5, "layers": [0], "falloff": 3, {sample}"#),
            "strokes[0].falloff: the number 3 where an object",
        ),
        (
            r#""brush": "draw", "radius": 0.1, "strength": 0.5, "layers": [0], "samples": [{"position": [1, 2]}]"#.to_string(),
            "strokes[0].samples[0].position: 2 numbers where 3 belong",
        ),
        (
            format!(r#""brush": "draw", "radius": 0.1, "strength": 0.5, "layers": 0, {sample}"#),
            "strokes[0].layers: the number 0 is not a list",
        ),
    ];
    for (fields, expected) in cases {
        let strokes = stroke_file(&dir, "s.json", &format!("{{{fields}}}"));
        let out = slayer(&[
            "sculpt",
            "--input",
            arg(&input),
            "--strokes",
            arg(&strokes),
            "--output",
            arg(&output),
        ]);
        assert_one_line_error(&out, &[expected]);
        let stderr = text(&out.stderr);
        for word in ["untagged", "expected value", "invalid type", "variant"] {
            assert!(!stderr.contains(word), "{stderr}");
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Item 1 as a user meets it: the issue's two far samples, and a count that would allocate
/// gigabytes, are refused at once with the bound and how to raise it.
#[test]
fn unbounded_work_is_refused_at_once_with_the_bound() {
    let dir = scratch("bounded");
    let input = dir.join("in.obj");
    write_scene("plane", 2000, &[], &input);
    let strokes = stroke_file(
        &dir,
        "far.json",
        r#"{"brush": "draw", "radius": 0.05, "strength": 0.5, "layers": [0],
            "samples": [{"position": [-0.26, 0.43, 0]}, {"position": [1e17, 0, 0]}]}"#,
    );
    let output = dir.join("out.obj");
    let limit = Duration::from_secs(20);
    let out = slayer_within(
        &[
            "sculpt",
            "--input",
            arg(&input),
            "--strokes",
            arg(&strokes),
            "--output",
            arg(&output),
        ],
        limit,
    );
    assert_one_line_error(&out, &["strokes[0]", "100000 allowed", "--max-dabs"]);
    assert!(!output.exists());
    let script = dir.join("s.json");
    let out = slayer_within(
        &["strokes", "--count", "100000000", "-o", arg(&script)],
        limit,
    );
    assert_one_line_error(&out, &["--count 100000000", "100000"]);
    assert!(!script.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

/// A grab pulling a tent out of a 390-face plane splits past a bound of 200 new faces (so 390,
/// the mesh's own faces): `sculpt` says where it stopped and how to raise it, writes the mesh,
/// and its stats count the capped pass; without the option the same stroke is not capped.
#[test]
fn a_stroke_that_grows_past_its_bound_of_new_faces_is_warned_of() {
    let dir = scratch("growth");
    let input = dir.join("in.ply");
    write_scene("plane", 400, &[], &input);
    let strokes = stroke_file(
        &dir,
        "tent.json",
        r#"{"brush": "grab", "radius": 0.35, "strength": 1.0, "layers": [0],
            "samples": [{"position": [0, 0, 0]}, {"position": [0, 0, 0.6]},
                        {"position": [0, 0, 1.2]}, {"position": [0, 0, 1.8]}]}"#,
    );
    let sculpt = |bound: Option<&str>| {
        let (output, stats) = (dir.join("out.ply"), dir.join("stats.json"));
        let mut args = vec!["sculpt", "--input", arg(&input), "--strokes", arg(&strokes)];
        args.extend(["--output", arg(&output), "--stats", arg(&stats)]);
        args.extend(bound.map(|b| ["--max-new-faces", b]).into_iter().flatten());
        let out = slayer(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let stats: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
        (text(&out.stderr), stats["strokes"][0]["remesh"].clone())
    };
    let (said, remesh) = sculpt(Some("200"));
    assert!(
        said.contains("strokes[0]: remeshing stopped splitting at 390 new faces")
            && said.contains("--max-new-faces"),
        "{said}"
    );
    assert!(remesh["growth_capped"].as_u64().unwrap() >= 1, "{remesh}");
    assert!(remesh["splits"].as_u64().unwrap() <= 195, "{remesh}");
    let (said, remesh) = sculpt(None);
    assert!(!said.contains("stopped splitting"), "{said}");
    assert_eq!(remesh["growth_capped"], 0, "{remesh}");
    assert!(remesh["splits"].as_u64().unwrap() > 195, "{remesh}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A sweep of nearly twice a sphere's size dragged ten times its size smears it into slivers
/// (soak stroke sphere #868 ran 25 minutes so): with `--max-stretch 8` the stroke stops at the
/// step that stretches an edge past 8 edge lengths, `sculpt` says so and how to raise it, and
/// writes a valid mesh; an absurd bound is refused in one line.
#[test]
fn a_stroke_that_stretches_past_its_bound_stops_and_is_warned_of() {
    let dir = scratch("stretch");
    let input = dir.join("in.ply");
    write_scene("sphere", 2_000, &[], &input);
    let strokes = stroke_file(
        &dir,
        "smear.json",
        r#"{"brush": "sweep", "radius": 3.2, "strength": 0.32, "layers": [0],
            "samples": [{"position": [2, 0, 0]}, {"position": [-10, 0.4, 0]}]}"#,
    );
    let (output, stats) = (dir.join("out.ply"), dir.join("stats.json"));
    let mut args = vec!["sculpt", "--input", arg(&input), "--strokes", arg(&strokes)];
    args.extend(["--output", arg(&output), "--stats", arg(&stats)]);
    let out = slayer(&[&args[..], &["--max-stretch", "8"]].concat());
    let said = text(&out.stderr);
    assert!(out.status.success(), "{said}");
    assert!(
        said.contains("strokes[0]: stopped after") && said.contains("--max-stretch"),
        "{said}"
    );
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    let stretched = stats["strokes"][0]["stopped_stretched"].as_f64().unwrap();
    assert!(stretched > 8.0, "{stretched}");
    let checked = slayer(&["check", arg(&output)]);
    assert!(checked.status.success(), "{}", text(&checked.stdout));
    let refused = slayer(&[&args[..], &["--max-stretch", "0.5"]].concat());
    assert_one_line_error(&refused, &["0.5", "from 2 to 1000000"]);
    std::fs::remove_dir_all(dir).unwrap();
}

/// `--edge-length` sets the `L` the strokes work at: the mesh's own mean edge length gives the
/// same mesh, byte for byte, as leaving it out; a coarser one another mesh; zero is refused.
#[test]
fn sculpt_works_at_the_edge_length_it_is_given() {
    let dir = scratch("edge_length");
    let input = dir.join("in.ply");
    write_scene("sphere", 2_000, &[], &input);
    let strokes = stroke_file(
        &dir,
        "draw.json",
        r#"{"brush": "draw", "radius": 0.3, "strength": 0.5, "layers": [0],
            "samples": [{"position": [0.5, 0, 0]}, {"position": [0.4, 0.2, 0]}]}"#,
    );
    let options = slayer::io::ImportOptions::default();
    let mean = slayer::io::load_mesh(&input, &options)
        .unwrap()
        .0
        .mean_edge_length();
    let sculpt = |extra: &[&str]| {
        let output = dir.join("out.ply");
        let mut args = vec!["sculpt", "--input", arg(&input), "--strokes", arg(&strokes)];
        args.extend(["--output", arg(&output)]);
        args.extend(extra);
        let out = slayer(&args);
        (out, std::fs::read(&output).unwrap_or_default())
    };
    let (plain, by_default) = sculpt(&[]);
    assert!(plain.status.success(), "{}", text(&plain.stderr));
    let (_, at_mean) = sculpt(&["--edge-length", &format!("{mean}")]);
    assert!(at_mean == by_default, "the mean edge length is the default");
    let (_, coarser) = sculpt(&["--edge-length", &format!("{}", 2.0 * mean)]);
    assert!(!coarser.is_empty() && coarser != by_default);
    let (refused, _) = sculpt(&["--edge-length", "0"]);
    assert_one_line_error(&refused, &["--edge-length 0", "positive"]);
    std::fs::remove_dir_all(dir).unwrap();
}

/// `slayer sculpt` killed with SIGKILL while it writes a 1M-face output: the previous output is
/// byte-identical, and the temporary file the killed run left is swept by the next write into
/// that folder.
#[test]
fn a_writer_killed_mid_write_leaves_the_previous_file_intact() {
    let dir = scratch("killed");
    let input = dir.join("big.ply");
    write_scene("plane", 1_000_000, &[], &input);
    let output = dir.join("out.ply");
    write_scene("plane", 200, &[], &output);
    let previous = std::fs::read(&output).unwrap();
    let strokes = stroke_file(&dir, "s.json", SMALL_STROKE);
    let is_temporary = |name: &str| name.starts_with(".out.ply.slayer-tmp.");
    let mut caught = false;
    // The temporary file lives for the write and its sync (tens of milliseconds at 1M faces):
    // a run that finished before it was seen is tried again on the previous file.
    for _ in 0..5 {
        std::fs::write(&output, &previous).unwrap();
        let mut child = Command::new(env!("CARGO_BIN_EXE_slayer"))
            .args(["sculpt", "--input", arg(&input), "--strokes", arg(&strokes)])
            .args(["--output", arg(&output), "--backend", "cpu"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("the binary runs");
        while child.try_wait().unwrap().is_none() {
            if listing(&dir).iter().any(|n| is_temporary(n)) {
                child.kill().unwrap(); // SIGKILL
                caught = true;
                break;
            }
            std::thread::sleep(Duration::from_micros(500));
        }
        child.wait().unwrap();
        if caught {
            break;
        }
    }
    assert!(caught, "never saw the writer's temporary file");
    assert!(
        std::fs::read(&output).unwrap() == previous,
        "the previous output changed"
    );
    assert!(
        listing(&dir).iter().any(|n| is_temporary(n)),
        "the kill left no temporary file"
    );
    write_scene("plane", 200, &[], &dir.join("next.ply"));
    let left: Vec<String> = listing(&dir)
        .into_iter()
        .filter(|n| n.contains(".slayer-tmp."))
        .collect();
    assert!(left.is_empty(), "stray temporary files: {left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
