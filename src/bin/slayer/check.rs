use std::path::Path;
use std::process::ExitCode;

use slayer::check::{CheckReport, check_mesh};

use crate::progress::Steps;

/// Loads and checks `file`; `Err` only for files that cannot be read as a mesh at all.
pub fn report(file: &Path) -> anyhow::Result<CheckReport> {
    let steps = Steps::new("check");
    steps.step("reading");
    let (mesh, notes) = if slayer::session::is_session_path(file) {
        let session = slayer::session::open(file)?;
        (session.into_mesh(), slayer::io::LoadNotes::default())
    } else {
        slayer::io::load_mesh(file)?
    };
    let report = check_mesh(&mesh, &notes, &file.display().to_string(), |s| {
        steps.step(s)
    });
    steps.finish();
    Ok(report)
}

pub fn run(file: &Path, json: bool) -> anyhow::Result<ExitCode> {
    let report = report(file)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("{report}");
    }
    Ok(if report.is_clean() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
