//! A seeded mutation run over every file slayer reads: OBJ (with its `.mtl`), PLY (ASCII and
//! binary), STL (ASCII and binary), glTF (`.glb`, `.gltf`), `.slayer` sessions and stroke files. Each mangled file must
//! give an `Err` or a valid mesh (a session, strokes that resolve), never a panic; each case runs
//! on a worker under a time box (a case past [`CASE_LIMIT`] fails the run: a hang), and the run's
//! peak memory is bounded. `tools/test.sh` runs a few thousand cases; `tools/fuzz.sh N` runs N (10⁵ takes a
//! few minutes) and prints the counts.

use std::sync::mpsc;
use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slayer::brush::StrokeFile;
use slayer::io::{Format, ImportOptions, encode_mesh, load_mesh_bytes, read_mesh_bytes};
use slayer::mesh::Mesh;
use slayer::session::{Session, read_session, write_session};

use slayer::scene::shapes;

/// Cases when `SLAYER_FUZZ_CASES` does not say.
const DEFAULT_CASES: usize = 5_000;
/// A case taking longer than this is a hang (the largest source parses in milliseconds).
const CASE_LIMIT: Duration = Duration::from_secs(5);
/// The whole run's peak resident memory may not pass this.
const PEAK_LIMIT_MIB: u64 = 2_048;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Mesh(Format),
    Session,
    Strokes,
}

/// What one case gave.
#[derive(Debug, Default)]
struct Counts {
    cases: usize,
    errors: usize,
    valid: usize,
    slowest: Duration,
}

fn sources() -> Vec<(Kind, Vec<u8>)> {
    let tiny = shapes::stacked_sheets(2, 3, 2, 1.0, 2.0);
    let mut sources = Vec::new();
    for mesh in [&tiny, &shapes::tetrahedron(), &shapes::fan(5)] {
        for format in [
            Format::Obj,
            Format::Ply,
            Format::Stl,
            Format::Glb,
            Format::Gltf,
        ] {
            sources.push((Kind::Mesh(format), encode_mesh(mesh, format)));
        }
        sources.push((
            Kind::Session,
            write_session(&Session::new(mesh.clone()), true),
        ));
    }
    let data = |name: &str| {
        std::fs::read(format!(
            "{}/tests/data/import/{name}",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap()
    };
    for (name, format) in [
        ("textured.obj", Format::Obj),
        ("untidy.obj", Format::Obj),
        ("colours.ply", Format::Ply),
        ("foreign_flags_be.ply", Format::Ply),
        ("two_solids.stl", Format::Stl),
        ("cad_tetra.stl", Format::Stl),
        ("two_nodes.gltf", Format::Gltf),
    ] {
        sources.push((Kind::Mesh(format), data(name)));
    }
    sources.push((Kind::Strokes, STROKES.as_bytes().to_vec()));
    sources
}

const STROKES: &str = r#"{"version": 1, "strokes": [
  {"brush": "draw", "radius": 0.4, "strength": 0.5, "falloff": {"curve": "blend", "n": 3},
   "layers": [0, "layer1"], "spacing": 0.25,
   "samples": [{"position": [0.2, 0.2, 0.0], "pressure": 1.0, "normal": [0, 0, 1]},
               {"position": [0.6, 0.4, 0.0], "pressure": 0.5}]},
  {"brush": "paint", "radius": 0.3, "strength": 1.0, "layers": [0], "symmetry": "x",
   "paint": {"material": "rust"}, "samples": [{"position": [0.5, 0.5, 0.0]}]}
]}"#;

/// Mangles a valid file in one of the ways real files break.
fn mangle(original: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut bytes = original.to_vec();
    match rng.random_range(0..10) {
        0 => bytes.truncate(rng.random_range(0..=bytes.len())),
        1 => {
            for _ in 0..rng.random_range(1..20) {
                let i = rng.random_range(0..bytes.len().max(1));
                if let Some(b) = bytes.get_mut(i) {
                    *b = rng.random();
                }
            }
        }
        2 => {
            bytes = (0..rng.random_range(0..200))
                .map(|_| rng.random())
                .collect()
        }
        3 => duplicate_lines(&mut bytes, rng),
        4 => bytes = nested_json(original, rng.random_range(1..100_000)),
        5 => {
            // A little-endian count anywhere made huge: binary headers that lie.
            if bytes.len() >= 4 {
                let i = rng.random_range(0..bytes.len() - 3);
                let lie: u32 = [u32::MAX, 1 << 31, 1_000_000_000, 0][rng.random_range(0..4)];
                bytes[i..i + 4].copy_from_slice(&lie.to_le_bytes());
            }
        }
        _ => replace_token(&mut bytes, rng),
    }
    bytes
}

fn duplicate_lines(bytes: &mut Vec<u8>, rng: &mut ChaCha8Rng) {
    let text = String::from_utf8_lossy(bytes).into_owned();
    let mut lines: Vec<&str> = text.split('\n').collect();
    for _ in 0..rng.random_range(1..5) {
        let i = rng.random_range(0..lines.len());
        let copies = rng.random_range(1..50);
        for _ in 0..copies {
            lines.insert(i, lines[i]);
        }
    }
    *bytes = lines.join("\n").into_bytes();
}

/// JSON nested `depth` deep, in the shape of a stroke file or, for a glTF, of its nodes.
fn nested_json(original: &[u8], depth: usize) -> Vec<u8> {
    let is_gltf =
        original.starts_with(b"glTF") || original.windows(7).take(64).any(|w| w == b"\"asset\"");
    let key = if is_gltf {
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": "
    } else {
        "{\"strokes\": "
    };
    let mut text = key.to_string();
    text.push_str(&"[".repeat(depth));
    text.push_str(&"]".repeat(depth));
    text.push('}');
    text.into_bytes()
}

/// Replaces one whitespace-separated token with an absurd one: counts that lie, NaN, infinity,
/// indices out of range, numbers too large for any type.
fn replace_token(bytes: &mut Vec<u8>, rng: &mut ChaCha8Rng) {
    const ABSURD: [&str; 20] = [
        "-1",
        "-999999",
        "0",
        "4294967296",
        "99999999999999999999",
        "1000000000000",
        "nan",
        "NaN",
        "inf",
        "-inf",
        "1e39",
        "1e30",
        "-0",
        "",
        "1.5",
        "0x10",
        "\n",
        "/",
        "//",
        "1//",
    ];
    let text = String::from_utf8_lossy(bytes).into_owned();
    let tokens: Vec<&str> = text.split(' ').collect();
    let i = rng.random_range(0..tokens.len());
    let mut out = tokens.clone();
    out[i] = ABSURD[rng.random_range(0..ABSURD.len())];
    *bytes = out.join(" ").into_bytes();
}

/// Reads `bytes` as `kind`; `true` for a valid result, `false` for an error. Panics (failing
/// the test) on an accepted result that is not valid.
fn try_case(kind: Kind, bytes: &[u8], mesh_for_strokes: &Mesh) -> bool {
    match kind {
        Kind::Mesh(format) => {
            // The lenient path `slayer check` takes must not panic either.
            let lenient = ImportOptions::default();
            let _ = load_mesh_bytes(
                bytes,
                format,
                "mangled",
                &lenient,
                &slayer::io::no_libraries,
            );
            match read_mesh_bytes(bytes, format, "mangled") {
                Ok(mesh) => {
                    mesh.validate().expect("an accepted mesh is valid");
                    assert!(mesh.positions().iter().all(|p| p.is_finite()));
                    true
                }
                Err(e) => {
                    assert!(!e.to_string().is_empty());
                    false
                }
            }
        }
        Kind::Session => match read_session(bytes, "mangled.slayer") {
            Ok(session) => {
                session
                    .mesh()
                    .validate()
                    .expect("an accepted session is valid");
                true
            }
            Err(e) => {
                assert!(!e.to_string().is_empty());
                false
            }
        },
        Kind::Strokes => {
            let text = String::from_utf8_lossy(bytes);
            StrokeFile::parse(&text, "mangled.json")
                .and_then(|file| file.resolve(mesh_for_strokes, "mangled.json"))
                .is_ok()
        }
    }
}

/// Runs cases on a worker thread, so that a case that never ends is caught by a timeout
/// instead of stalling the run: the test fails, naming and saving the case.
struct Worker {
    cases: mpsc::Sender<(Kind, Vec<u8>)>,
    results: mpsc::Receiver<bool>,
}

impl Worker {
    fn start() -> Worker {
        let (cases, inbox) = mpsc::channel::<(Kind, Vec<u8>)>();
        let (outbox, results) = mpsc::channel();
        std::thread::spawn(move || {
            let sheet = shapes::stacked_sheets(2, 3, 2, 1.0, 2.0);
            for (kind, bytes) in inbox {
                // A panic drops `outbox`, which the waiting side sees as a failed case.
                let valid = try_case(kind, &bytes, &sheet);
                if outbox.send(valid).is_err() {
                    return;
                }
            }
        });
        Worker { cases, results }
    }

    /// The case's outcome, or why it has none: it panicked, or it ran past [`CASE_LIMIT`].
    fn run(&self, kind: Kind, bytes: &[u8]) -> Result<bool, String> {
        self.cases
            .send((kind, bytes.to_vec()))
            .map_err(|_| "the worker is gone (an earlier case panicked)".to_string())?;
        self.results.recv_timeout(CASE_LIMIT).map_err(|e| match e {
            mpsc::RecvTimeoutError::Timeout => format!("ran past {CASE_LIMIT:?} (a hang)"),
            mpsc::RecvTimeoutError::Disconnected => "panicked".to_string(),
        })
    }
}

#[test]
fn mangled_files_of_every_kind_give_an_error_or_a_valid_result() {
    let cases = std::env::var("SLAYER_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(DEFAULT_CASES);
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    let sources = sources();
    let worker = Worker::start();
    let mut counts = Counts::default();
    for case in 0..cases {
        let (kind, original) = &sources[case % sources.len()];
        let bytes = mangle(original, &mut rng);
        let started = Instant::now();
        let valid = worker.run(*kind, &bytes).unwrap_or_else(|why| {
            let path = std::env::temp_dir().join(format!("slayer-fuzz-case-{case}"));
            std::fs::write(&path, &bytes).unwrap();
            panic!("case {case} ({kind:?}) {why}; saved in {}", path.display());
        });
        counts.cases += 1;
        counts.slowest = counts.slowest.max(started.elapsed());
        if valid {
            counts.valid += 1;
        } else {
            counts.errors += 1;
        }
    }
    let peak = slayer::memory::peak_resident_bytes().map(|b| b >> 20);
    eprintln!(
        "fuzz: {} cases, {} errors, {} valid, 0 panics, 0 hangs, slowest case {:?}, peak RSS {} MiB",
        counts.cases,
        counts.errors,
        counts.valid,
        counts.slowest,
        peak.map_or("unknown".into(), |p| p.to_string())
    );
    assert!(
        counts.valid > cases / 20 && counts.errors > cases / 4,
        "both outcomes are exercised: {counts:?}"
    );
    if let Some(peak) = peak {
        assert!(peak < PEAK_LIMIT_MIB, "peak RSS {peak} MiB");
    }
}
