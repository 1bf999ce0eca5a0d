//! `slayer history` and `slayer undo`: a session file's history, headless.

use std::path::Path;
use std::process::ExitCode;

use anyhow::Context;
use slayer::session::{Session, is_session_path};

fn open_session(path: &Path) -> anyhow::Result<Session> {
    if !is_session_path(path) {
        anyhow::bail!(
            "{}: only a session file (.slayer) keeps a history",
            path.display()
        );
    }
    Ok(slayer::session::open(path)?)
}

/// Lists a session's history entries, oldest first, with the bytes each holds.
pub fn list(path: &Path, json: bool) -> anyhow::Result<ExitCode> {
    let session = open_session(path)?;
    let history = session.history();
    let mesh_bytes = session.mesh().memory_bytes();
    if json {
        let entries: Vec<_> = history
            .entries()
            .iter()
            .enumerate()
            .map(|(i, e)| {
                serde_json::json!({
                    "index": i + 1,
                    "label": e.label,
                    "bytes": e.bytes(),
                    "done": i < history.done(),
                })
            })
            .collect();
        let json = serde_json::json!({
            "file": path.display().to_string(),
            "entries": entries,
            "done": history.done(),
            "bytes": history.bytes(),
            "cap_bytes": history.cap_bytes(),
            "mesh_bytes": mesh_bytes,
        });
        println!("{}", serde_json::to_string_pretty(&json)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "{}: {} entries ({} done), {:.2} MiB of history for a mesh of {:.2} MiB (cap {} MiB)",
        path.display(),
        history.entries().len(),
        history.done(),
        history.bytes() as f64 / 1048576.0,
        mesh_bytes as f64 / 1048576.0,
        history.cap_bytes() >> 20
    );
    for (i, entry) in history.entries().iter().enumerate() {
        let state = if i < history.done() { "" } else { "  (undone)" };
        println!(
            "  {:>4}  {:<28} {:>10} bytes{state}",
            i + 1,
            entry.label,
            entry.bytes()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Which way `slayer undo` / `slayer redo` steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    Undo,
    Redo,
}

/// Undoes (or redoes) `steps` entries of a session file's history and writes the result.
pub fn step(path: &Path, way: Step, steps: usize, output: &Path) -> anyhow::Result<ExitCode> {
    slayer::session::check_save_path(output)?;
    let mut session = open_session(path)?;
    let history = session.history();
    let (available, verb, what) = match way {
        Step::Undo => (history.done(), "undid", "to undo"),
        Step::Redo => (history.entries().len() - history.done(), "redid", "to redo"),
    };
    if steps > available {
        anyhow::bail!(
            "{}: --steps {steps} is more than the {available} entries there are {what}",
            path.display()
        );
    }
    let started = std::time::Instant::now();
    for _ in 0..steps {
        match way {
            Step::Undo => session.undo(),
            Step::Redo => session.redo(),
        };
    }
    let millis = started.elapsed().as_secs_f64() * 1e3;
    session
        .mesh()
        .validate()
        .context("the mesh after stepping through the history failed validation (not written)")?;
    slayer::session::save(&session, output, true)?;
    let history = session.history();
    println!(
        "{verb} {steps} of {available} entries in {millis:.1} ms -> {} ({} left to undo, {} to redo)",
        output.display(),
        history.done(),
        history.entries().len() - history.done()
    );
    Ok(ExitCode::SUCCESS)
}
