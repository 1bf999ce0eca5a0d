//! The full soak runs for hours, longer than one sitting: with `SLAYER_SOAK_CHECKPOINT=DIR` each
//! scene's run is saved at every check that passed (the session with its whole history, the
//! random stream's position, the counts so far) and taken up again from there by the next run
//! with the same `DIR`, stroke for stroke as if it had never stopped.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use slayer::scene::SceneKind;
use slayer::session::Session;

/// Where a scene's soak stands after a check.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Progress {
    /// The strokes asked for and the scene's faces: a checkpoint of another size is refused.
    pub strokes: usize,
    pub faces: usize,
    /// The next stroke to run, and the digest of the mesh it runs on.
    pub next: usize,
    pub digest: String,
    /// The random stream's word position (a `u128`, as text) at `next`.
    pub word_pos: String,
    /// The pipeline's edge length `L`, as bits: held from the first stroke, as it was.
    pub edge_length_bits: Option<u32>,
    pub refused: usize,
    pub collisions: usize,
    pub undone: usize,
    /// History entries dropped for the memory cap (the history saved holds the rest).
    pub dropped: usize,
    /// Strokes that stopped where they stretched an edge past their bound (a checkpoint saved
    /// before they were counted reads 0).
    #[serde(default)]
    pub stopped: usize,
    pub slowest_seconds: f64,
    pub slowest: String,
    /// The stroke that took the most processor time (all threads), and that time: unlike the
    /// wall-clock figure, not inflated by whatever else runs beside the soak or by pausing it
    /// (a checkpoint saved before it was counted reads 0).
    #[serde(default)]
    pub slowest_cpu_seconds: f64,
    #[serde(default)]
    pub slowest_cpu: String,
    /// Seconds the strokes took in the sittings before this one.
    pub seconds: f64,
}

impl Progress {
    /// A run of `strokes` on `faces` about to begin.
    pub fn new(strokes: usize, faces: usize) -> Progress {
        Progress {
            strokes,
            faces,
            ..Progress::default()
        }
    }
}

/// The checkpoint folder, if one was asked for.
pub fn folder() -> Option<PathBuf> {
    std::env::var_os("SLAYER_SOAK_CHECKPOINT").map(PathBuf::from)
}

fn paths(dir: &Path, kind: SceneKind) -> (PathBuf, PathBuf) {
    let name = format!("{kind:?}").to_lowercase();
    (
        dir.join(format!("{name}.slayer")),
        dir.join(format!("{name}.json")),
    )
}

/// The session and progress saved for `kind` in `dir`, if any; panics on a checkpoint of
/// another soak size (`strokes`, `faces`) rather than mixing two runs.
pub fn resume(
    dir: &Path,
    kind: SceneKind,
    strokes: usize,
    faces: usize,
) -> Option<(Session, Progress)> {
    let (session_path, progress_path) = paths(dir, kind);
    let text = std::fs::read_to_string(&progress_path).ok()?;
    let progress: Progress =
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", progress_path.display()));
    assert!(
        progress.strokes == strokes && progress.faces == faces,
        "{}: a checkpoint of {} strokes on {} faces, not of {strokes} on {faces}",
        progress_path.display(),
        progress.strokes,
        progress.faces
    );
    let session = slayer::session::open(&session_path)
        .unwrap_or_else(|e| panic!("{}: {e}", session_path.display()));
    assert_eq!(
        session.mesh().digest(),
        progress.digest,
        "{}: not the mesh its progress was saved with",
        session_path.display()
    );
    Some((session, progress))
}

/// Saves `session` and `progress` for `kind` in `dir`, both or neither.
pub fn save(dir: &Path, kind: SceneKind, session: &Session, progress: &Progress) {
    std::fs::create_dir_all(dir).unwrap();
    let (session_path, progress_path) = paths(dir, kind);
    let json = serde_json::to_string_pretty(progress).unwrap();
    let mut batch = slayer::io::AtomicBatch::new();
    slayer::session::stage(&mut batch, session, &session_path, true).unwrap();
    batch.stage(&progress_path, json.as_bytes()).unwrap();
    batch.commit().unwrap();
}
