//! Opening the file a command works on: a session, or a mesh file repaired unless `--strict`,
//! with what the import repaired and left out said on stderr (stdout stays the command's).

use std::path::Path;

use slayer::io::ImportOptions;
use slayer::session::Session;

/// Opens `path` (`strict`: refuse a mesh file that needs repairs) and says what was repaired.
pub fn open(path: &Path, strict: bool) -> anyhow::Result<Session> {
    let (session, report) = slayer::session::open_with(path, &ImportOptions { strict })?;
    say_repairs(path, &report);
    Ok(session)
}

/// [`open`] for a batch whose result is a mesh file: the session keeps no history (no copy
/// of the mesh to undo to), and a session file's history is dropped.
pub fn open_without_history(path: &Path, strict: bool) -> anyhow::Result<Session> {
    let mut session = open(path, strict)?;
    session.drop_history();
    Ok(session)
}

fn say_repairs(path: &Path, report: &slayer::io::ImportReport) {
    let shown = slayer::files::escape(&path.display().to_string()).into_owned();
    for line in report.lines() {
        eprintln!("{shown}: {line}");
    }
}
