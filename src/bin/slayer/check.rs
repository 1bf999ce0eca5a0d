use std::path::Path;
use std::process::ExitCode;

use slayer::check::{CheckReport, check_mesh};
use slayer::io::{ImportOptions, ImportReport};

use crate::progress::Steps;

/// Loads and checks `file` (against the file it was made from, if given); `Err` only for
/// files that cannot be read as a mesh at all.
pub fn report(file: &Path, against: Option<&Path>, strict: bool) -> anyhow::Result<CheckReport> {
    let steps = Steps::new("check");
    steps.step("reading");
    let (mesh, notes) = load(file, strict)?;
    let original = against.map(|path| load(path, strict)).transpose()?;
    let mut report = check_mesh(&mesh, &notes, &file.display().to_string(), |s| {
        steps.step(s)
    });
    if let Some((original, _)) = &original {
        steps.step("comparing closed volumes with the original");
        report.compare_with(&mesh, original);
    }
    steps.finish();
    Ok(report)
}

/// The mesh, and what reading it repaired and left out (which the report shows, so it is not
/// printed here).
fn load(file: &Path, strict: bool) -> anyhow::Result<(slayer::mesh::Mesh, ImportReport)> {
    Ok(if slayer::session::is_session_path(file) {
        let session = slayer::session::open(file)?;
        let notes = ImportReport {
            fuse_layers: session.all_fuse_layers(),
            ..ImportReport::default()
        };
        (session.into_mesh(), notes)
    } else {
        slayer::io::load_mesh(file, &ImportOptions { strict })?
    })
}

pub fn run(
    file: &Path,
    json: bool,
    against: Option<&Path>,
    strict: bool,
) -> anyhow::Result<ExitCode> {
    let report = report(file, against, strict)?;
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
