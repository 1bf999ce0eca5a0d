//! The soak test: random strokes of every brush, with random layers, radii (extreme ones
//! included), strengths and pressures, remeshing on, over plaster and a closed sphere, checked
//! exactly every 25 strokes — 0 intersecting triangle pairs, layers at least the collision
//! distance apart, `validate()`, bounded growth and memory, each stroke within its bound of new
//! faces (what bounds its time) — through the session, so every stroke is also
//! undone at the end back to the input (and, where strokes grew the mesh past four times its
//! faces, undone on the way back to twice).
//!
//! The short version, in `tools/test.sh`: 200 strokes in all on ~2K faces (about 25 s
//! on two cores). The full one, 10⁴ strokes on ~20K faces:
//! `SLAYER_SOAK_STROKES=10000 cargo test --release --test soak -- --nocapture`. Times are
//! printed, never asserted: wall-clock and processor time (all threads; the scenes run one at a
//! time), the second the one to trust when anything else ran beside the soak or paused it.
//! `SLAYER_SOAK_CHECK_EVERY=1` checks after every stroke; `SLAYER_SOAK_TRACE=1` prints each
//! stroke (as a stroke file) before it runs; `SLAYER_SOAK_DUMP=N:DIR` writes the mesh before
//! stroke `N`, the stroke and `L` into `DIR` (`SLAYER_SOAK_DUMP=each:DIR` before every stroke,
//! over the last, to catch one that never ends).
//! `SLAYER_SOAK_CHECKPOINT=DIR` saves each scene's run at every check and takes it up from
//! there the next time (`checkpoint`): the full soak over several sittings. A run taken up
//! goes on with the same random stream on the saved session, history included, but with its
//! pipeline set up afresh as a new process's is, so it need not match an unbroken run to the
//! bit.

#[path = "soak/checkpoint.rs"]
mod checkpoint;

use std::time::Instant;

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slayer::brush::{BrushKind, LayerRef, SampleSpec, Stroke, StrokeFile, StrokeSpec};
use slayer::collide::{find_intersections, smallest_layer_gap};
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings};
use slayer::scene::{SceneKind, SceneSpec, generate};
use slayer::session::Session;

use checkpoint::Progress;

/// Strokes between exact checks (`SLAYER_SOAK_CHECK_EVERY` to narrow a failure down).
fn check_every() -> usize {
    std::env::var("SLAYER_SOAK_CHECK_EVERY")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(25)
}

/// The short version, in `tools/test.sh`: strokes in all (half on each scene) and faces.
const SHORT_STROKES: usize = 200;
const SHORT_FACES: usize = 2_000;

/// The surface grows where strokes pull it out (the sphere by about 300 faces a stroke at 20K,
/// 1,000 at 45K): past this many times its faces after a stroke, strokes are undone until it is
/// back under half that, so that a soak of 10⁴ strokes stays one of its size, and undo runs in
/// the middle of it.
const GROWTH_UNDONE: usize = 4;

/// Strokes in all, and the faces of each scene: the short version's, or what
/// `SLAYER_SOAK_STROKES` asks for, on `SLAYER_SOAK_FACES` (20K unless given).
fn size() -> (usize, usize) {
    let number = |name: &str| std::env::var(name).ok().and_then(|s| s.parse().ok());
    match number("SLAYER_SOAK_STROKES") {
        Some(strokes) => (strokes, number("SLAYER_SOAK_FACES").unwrap_or(20_000)),
        None => (SHORT_STROKES, SHORT_FACES),
    }
}

/// A random stroke: any brush, a random subset of layers, a radius from a twentieth of an edge
/// to far past the mesh (some refused), a path of 1 to 8 samples from a vertex.
fn random_stroke(mesh: &Mesh, rng: &mut ChaCha8Rng) -> StrokeSpec {
    let edge = mesh.mean_edge_length();
    let brush = BrushKind::ALL[rng.random_range(0..BrushKind::ALL.len())];
    let radius = match rng.random_range(0..10) {
        0 => edge * rng.random_range(0.04..0.5),
        1 => edge * rng.random_range(100.0..2000.0),
        _ => edge * rng.random_range(2.0..30.0),
    };
    let mut layers: Vec<LayerRef> = (0..mesh.layer_count() as u32)
        .filter(|_| rng.random_bool(0.6))
        .map(LayerRef::Index)
        .collect();
    if layers.is_empty() {
        layers.push(LayerRef::Index(0));
    }
    let start = loop {
        let v = rng.random_range(0..mesh.vertex_count()) as u32;
        if !mesh.is_vertex_dead(v) {
            break mesh.positions()[v as usize];
        }
    };
    let direction = Vec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        0.0,
    );
    let step = direction.normalize_or_zero() * radius * rng.random_range(0.1..1.0);
    let samples = (0..rng.random_range(1..=8))
        .map(|i| SampleSpec {
            position: (start + step * i as f32).to_array(),
            pressure: rng.random_range(0.0..=1.0),
            normal: None,
        })
        .collect();
    StrokeSpec {
        brush,
        radius,
        strength: rng.random_range(0.0..=1.0),
        falloff: Default::default(),
        invert: rng.random_bool(0.3),
        layers,
        paint: (brush == BrushKind::Paint).then(|| slayer::brush::PaintSpec::material("rust")),
        spacing: 0.25,
        symmetry: None,
        samples,
    }
}

/// The scenes run one at a time, so that the process's processor time over a stroke is that
/// stroke's alone (the test harness runs tests side by side).
static ONE_SCENE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Runs half of [`size`]'s strokes, drawn from `seed`, on the scene `kind` at its faces (the
/// scene's own seed 9), and checks it every [`check_every`] strokes.
fn soak(kind: SceneKind, seed: u64) {
    // A scene that failed poisons the lock; the other still runs.
    let _alone = ONE_SCENE_AT_A_TIME
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let (strokes, faces) = size();
    let count = strokes / 2;
    let input = generate(&SceneSpec {
        kind,
        triangles: faces,
        seed: 9,
    })
    .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let checkpoints = checkpoint::folder();
    let (mut session, mut progress) = begin(
        checkpoints.as_deref(),
        kind,
        (strokes, faces),
        &input,
        &mut rng,
    );
    // A run taken up holds the edge length its first stroke measured, as the run did.
    let mut pipeline = Pipeline::new(PipelineSettings {
        edge_length: progress.edge_length_bits.map(f32::from_bits),
        ..PipelineSettings::default()
    });
    let faces_at_start = input.live_face_count();
    let edge_at_start = input.mean_edge_length();
    let (dropped_earlier, seconds_earlier) = (progress.dropped, progress.seconds);
    let soak_started = Instant::now();
    for i in progress.next..count {
        let spec = random_stroke(session.mesh(), &mut rng);
        let file = StrokeFile {
            version: 1,
            strokes: vec![spec],
            fuse: Vec::new(),
        };
        let as_json = serde_json::to_string(&file).unwrap_or_default();
        run_stroke(
            kind,
            (i, &file, &as_json),
            &mut session,
            &mut pipeline,
            &mut progress,
        );
        progress.seconds = seconds_earlier + soak_started.elapsed().as_secs_f64();
        progress.dropped = dropped_earlier + session.history().dropped();
        let checked = (i + 1) % check_every() == 0 || i + 1 == count;
        if checked {
            let mesh = session.mesh();
            if count > SHORT_STROKES / 2 {
                // The full version runs for hours: say how far it has come.
                eprintln!(
                    "{kind:?}: {} strokes in {:.0} s, {} faces, {} collisions, {} refused, {} undone (history {:.1} MiB, {} entries dropped)",
                    i + 1,
                    progress.seconds,
                    mesh.live_face_count(),
                    progress.collisions,
                    progress.refused,
                    progress.undone,
                    session.history().bytes() as f64 / 1048576.0,
                    progress.dropped
                );
            }
            let start = (faces_at_start, edge_at_start);
            check_sound(kind, (i, &as_json), mesh, pipeline.edge_length(), start);
            check_memory(kind, i);
        }
        // After every stroke, not only at checks: 100 strokes took the 20K sphere to 148K
        // faces between two checks, and each stroke grew slower with it.
        progress.undone += undo_growth(&mut session, faces_at_start);
        if let (true, Some(dir)) = (checked, &checkpoints) {
            progress.next = i + 1;
            progress.digest = session.mesh().digest();
            progress.word_pos = rng.get_word_pos().to_string();
            progress.edge_length_bits = pipeline.edge_length().map(f32::to_bits);
            checkpoint::save(dir, kind, &session, &progress);
        }
    }
    print_summary(kind, count, &progress, &session, faces_at_start);
    while session.undo().is_some() {}
    if progress.dropped == 0 {
        assert_eq!(
            session.mesh().digest(),
            input.digest(),
            "{kind:?}: undo all"
        );
    }
}

/// The session and progress the run starts from: its checkpoint's, if `folder` holds one for
/// a soak of this size, with `rng` moved on to where it stood; else `input`, at stroke 0.
fn begin(
    folder: Option<&std::path::Path>,
    kind: SceneKind,
    (strokes, faces): (usize, usize),
    input: &Mesh,
    rng: &mut ChaCha8Rng,
) -> (Session, Progress) {
    match folder.and_then(|dir| checkpoint::resume(dir, kind, strokes, faces)) {
        Some((session, progress)) => {
            eprintln!("{kind:?}: taken up at stroke {}", progress.next);
            rng.set_word_pos(progress.word_pos.parse().unwrap());
            (session, progress)
        }
        None => (Session::new(input.clone()), Progress::new(strokes, faces)),
    }
}

/// Runs stroke `i` (`file`, `as_json` for messages) through the session, counting it in
/// `progress`: refused (before it runs or by the pipeline), its collisions, its time. A stroke
/// must stay within its bound of new faces.
fn run_stroke(
    kind: SceneKind,
    (i, file, as_json): (usize, &StrokeFile, &str),
    session: &mut Session,
    pipeline: &mut Pipeline,
    progress: &mut Progress,
) {
    let Ok(strokes) = file.resolve(session.mesh(), "soak") else {
        progress.refused += 1;
        return;
    };
    if std::env::var("SLAYER_SOAK_TRACE").is_ok() {
        eprintln!("stroke {i}: {as_json}");
    }
    dump_before(i, session.mesh(), as_json, pipeline.edge_length());
    let started = Instant::now();
    let cpu_started = process_cpu_seconds();
    let faces_before = session.mesh().live_face_count();
    let phases = match session.apply_stroke(pipeline, &strokes[0]) {
        Ok((report, _)) => {
            progress.collisions += report.clamped;
            progress.stopped += usize::from(report.stopped_stretched.is_some());
            // The stroke's bound on the faces its remeshing creates (two a split at most),
            // which also bounds its time: a crease over all of the plaster once crumpled it
            // from 53K to 212K faces in 2 minutes.
            let bound = PipelineSettings::default().new_faces_bound(faces_before);
            assert!(
                2 * report.remesh.splits <= bound,
                "{kind:?} stroke {i}: {} splits, the bound {bound} faces: {as_json}",
                report.remesh.splits
            );
            Some(report.phases)
        }
        Err(_) => {
            progress.refused += 1;
            None
        }
    };
    let seconds = started.elapsed().as_secs_f64();
    let cpu_seconds = process_cpu_seconds() - cpu_started;
    if seconds > 2.0 {
        let (collision, remesh) = phases.map_or((0.0, 0.0), |p| (p.collision, p.remesh));
        eprintln!(
            "{kind:?} stroke {i}: {seconds:.1} s, processor {cpu_seconds:.1} s (collision {:.1} s, remesh {:.1} s), {}",
            collision / 1e3,
            remesh / 1e3,
            describe(&strokes[0])
        );
    }
    if seconds > progress.slowest_seconds {
        progress.slowest_seconds = seconds;
        progress.slowest = describe(&strokes[0]);
    }
    if cpu_seconds > progress.slowest_cpu_seconds {
        progress.slowest_cpu_seconds = cpu_seconds;
        progress.slowest_cpu = describe(&strokes[0]);
    }
}

/// The soak's figures for one scene, printed at its end.
fn print_summary(
    kind: SceneKind,
    count: usize,
    progress: &Progress,
    session: &Session,
    faces_at_start: usize,
) {
    let peak = slayer::memory::peak_resident_bytes();
    eprintln!(
        "{kind:?}: {count} strokes in {:.0} s, {} refused, {} collisions, {} stopped for stretching an edge past its bound, {} undone to keep the size, slowest {:.2} s ({}), slowest in processor time {:.2} s ({}), {} → {} faces (digest {}), history {:.1} MiB, {} entries dropped, peak memory of the test process {}",
        progress.seconds,
        progress.refused,
        progress.collisions,
        progress.stopped,
        progress.undone,
        progress.slowest_seconds,
        progress.slowest,
        progress.slowest_cpu_seconds,
        progress.slowest_cpu,
        faces_at_start,
        session.mesh().live_face_count(),
        &session.mesh().digest()[..16],
        session.history().bytes() as f64 / 1048576.0,
        progress.dropped,
        peak.map_or("unknown".into(), |b| format!(
            "{:.0} MiB",
            b as f64 / 1048576.0
        ))
    );
}

/// Processor seconds this process has used, all threads (`/proc/self/stat`'s user and system
/// times, in the kernel's fixed 100 ticks a second); 0 where that cannot be read.
fn process_cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // The fields after the command name (which may hold spaces) start at the third:
    // user time is the 14th, system time the 15th.
    let after_name = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    let ticks: u64 = after_name
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|t| t.parse::<u64>().ok())
        .sum();
    ticks as f64 / 100.0
}

/// A stroke in a few words, for the printout of slow strokes.
fn describe(s: &Stroke) -> String {
    let brush = &s.brush;
    format!(
        "{:?} radius {:.4} strength {} over {} samples",
        brush.kind,
        brush.radius,
        brush.strength,
        s.samples.len()
    )
}

/// The exact checks after stroke `i` (`last`, as a stroke file, for the messages): a valid mesh,
/// 0 crossings, layers the collision distance apart, growth within a bound and the edge length
/// kept. `edge` is the pipeline's `L`; `start` the faces and mean edge the scene began with.
fn check_sound(
    kind: SceneKind,
    (i, last): (usize, &str),
    mesh: &Mesh,
    edge: Option<f32>,
    (faces_at_start, edge_at_start): (usize, f32),
) {
    mesh.validate()
        .unwrap_or_else(|e| panic!("{kind:?} stroke {i}: {e}"));
    let crossings = find_intersections(mesh).total();
    assert_eq!(
        crossings, 0,
        "{kind:?}: {crossings} crossings after stroke {i}, the last {last}"
    );
    // Layers stay the collision distance apart (the pipeline's `d`, 1·L), remeshing
    // included.
    let d = edge.unwrap_or(edge_at_start) * PipelineSettings::default().collision_distance;
    let gap = smallest_layer_gap(mesh, 3.0 * d).unwrap();
    assert!(
        gap.is_none_or(|g| g >= 0.99 * d),
        "{kind:?}: layers {gap:?} apart after stroke {i} (d = {d}), the last {last}"
    );
    // Remeshing keeps the edge length; the surface grows where grabs pull it out (a
    // grab as wide as the sphere dragged five of its radii out of a crumpled side
    // grew it from 18K to 60K faces), but within a bound.
    let faces = mesh.live_face_count();
    let mean_edge = mesh.mean_edge_length();
    assert!(
        faces < 32 * faces_at_start,
        "{kind:?}: {faces} faces after stroke {i}"
    );
    assert!(
        (0.5 * edge_at_start..=1.5 * edge_at_start).contains(&mean_edge),
        "{kind:?}: mean edge {mean_edge} after stroke {i}, {edge_at_start} at the start"
    );
}

/// Past [`GROWTH_UNDONE`] times the faces it began with, strokes are undone until the mesh is
/// back under half that; returns how many.
fn undo_growth(session: &mut Session, faces_at_start: usize) -> usize {
    let mut undone = 0;
    if session.mesh().live_face_count() > GROWTH_UNDONE * faces_at_start {
        while session.mesh().live_face_count() > GROWTH_UNDONE / 2 * faces_at_start
            && session.undo().is_some()
        {
            undone += 1;
        }
    }
    undone
}

/// With `SLAYER_SOAK_DUMP=N:DIR`, writes the mesh before stroke `N` to `DIR/before.ply`, the
/// stroke to `DIR/stroke.json` and the pipeline's edge length to `DIR/edge_length`, for
/// `slayer sculpt --edge-length` to replay it alone; with `each:DIR`,
/// before every stroke (each over the last: what is there when a stroke never ends is its own).
fn dump_before(stroke: usize, mesh: &Mesh, stroke_json: &str, edge_length: Option<f32>) {
    let Ok(spec) = std::env::var("SLAYER_SOAK_DUMP") else {
        return;
    };
    let Some((at, dir)) = spec.split_once(':') else {
        return;
    };
    if at == "each" || at.parse() == Ok(stroke) {
        let dir = std::path::Path::new(dir);
        slayer::io::write_mesh(mesh, &dir.join("before.ply")).unwrap();
        std::fs::write(dir.join("stroke.json"), stroke_json).unwrap();
        // The L the soak's pipeline holds: `slayer sculpt --edge-length` replays at it.
        let edge = edge_length.map_or(String::new(), |l| format!("{l}\n"));
        std::fs::write(dir.join("edge_length"), edge).unwrap();
    }
}

/// The test process's peak memory stays under this, both scenes together: each session's
/// history is capped at 512 MiB and each mesh at [`GROWTH_UNDONE`] times its faces at a check
/// (the full soak's plaster peaked at 324 MB over 300 strokes; the short version at 44 MB).
const MEMORY_BOUND: u64 = 3 << 30;

fn check_memory(kind: SceneKind, i: usize) {
    if let Some(peak) = slayer::memory::peak_resident_bytes() {
        assert!(
            peak < MEMORY_BOUND,
            "{kind:?} stroke {i}: the process peaked at {peak} bytes"
        );
    }
}

#[test]
fn random_strokes_on_plaster_keep_it_sound() {
    soak(SceneKind::Plaster, 41);
}

#[test]
fn random_strokes_on_a_closed_sphere_keep_it_sound() {
    soak(SceneKind::Sphere, 43);
}

/// A checkpoint gives back the session (mesh and history) and progress it saved, and the
/// random stream goes on from where it stood.
#[test]
fn a_checkpoint_takes_a_run_up_where_it_stood() {
    let input = generate(&SceneSpec {
        kind: SceneKind::Sphere,
        triangles: 500,
        seed: 9,
    })
    .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut session = Session::new(input.clone());
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    let mut progress = Progress::new(10, 500);
    for i in 0..3 {
        let file = StrokeFile {
            version: 1,
            strokes: vec![random_stroke(session.mesh(), &mut rng)],
            fuse: Vec::new(),
        };
        run_stroke(
            SceneKind::Sphere,
            (i, &file, ""),
            &mut session,
            &mut pipeline,
            &mut progress,
        );
    }
    progress.next = 3;
    progress.digest = session.mesh().digest();
    progress.word_pos = rng.get_word_pos().to_string();
    let dir = std::env::temp_dir().join(format!("slayer-soak-checkpoint-{}", std::process::id()));
    checkpoint::save(&dir, SceneKind::Sphere, &session, &progress);
    let (mut taken_up, saved) = checkpoint::resume(&dir, SceneKind::Sphere, 10, 500).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(taken_up.mesh().digest(), session.mesh().digest());
    assert_eq!(taken_up.history().done(), session.history().done());
    assert!(taken_up.history().done() > 0, "no stroke ran");
    assert_eq!(
        (saved.next, saved.refused, saved.collisions),
        (3, progress.refused, progress.collisions)
    );
    let mut again = ChaCha8Rng::seed_from_u64(7);
    again.set_word_pos(saved.word_pos.parse().unwrap());
    let next: u64 = rng.random();
    assert_eq!(again.random::<u64>(), next);
    while taken_up.undo().is_some() {}
    assert_eq!(taken_up.mesh().digest(), input.digest());
}
