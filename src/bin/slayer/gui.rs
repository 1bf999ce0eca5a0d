//! `slayer gui [FILE]`: the sculpting app, and its headless hooks (`--replay`, `--screenshot`,
//! `--save`, `--exit-after-frames`) for tests, docs and measurements.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use slayer::app::{AppSetup, ExitPlan};
use slayer::brush::StrokeFile;
use slayer::pipeline::PipelineSettings;
use slayer::scene::{SceneKind, SceneSpec, generate};
use slayer::session::Session;

pub struct Args<'a> {
    pub file: Option<&'a Path>,
    /// Triangles of the default plaster when no file is given.
    pub triangles: usize,
    pub replay: Option<&'a Path>,
    pub plan: ExitPlan,
    pub window: (u32, u32),
    pub antialias: bool,
    /// `auto`, `shared` or `own`: the window's device when the engine is on the GPU.
    pub device: &'a str,
    pub backend: crate::backend::Backend,
    pub strict: bool,
}

pub fn run(args: Args<'_>) -> anyhow::Result<ExitCode> {
    if let Some(path) = &args.plan.save {
        slayer::session::check_save_path(path)?;
    }
    let session = match args.file {
        Some(path) => crate::open::open(path, args.strict)?,
        None => Session::new(generate(&SceneSpec {
            triangles: args.triangles,
            ..SceneSpec::new(SceneKind::Plaster)
        })?),
    };
    let replay = match args.replay {
        Some(path) => {
            let text = slayer::files::read_input_text(path, slayer::files::MAX_INPUT_BYTES)
                .with_context(|| format!("{}", path.display()))?;
            let name = path.display().to_string();
            StrokeFile::parse(&text, &name)?.resolve(session.mesh(), &name)?
        }
        None => Vec::new(),
    };
    let (chosen, shared) =
        crate::backend::choose_sharing(args.backend, PipelineSettings::default())?;
    eprintln!(
        "slayer gui: {} faces, sculpting on {}",
        session.mesh().live_face_count(),
        chosen.adapter
    );
    let save_path = args
        .file
        .map(slayer::app::save_path_for)
        .unwrap_or_else(|| PathBuf::from("untitled.slayer"));
    let setup = AppSetup {
        session,
        pipeline: chosen.pipeline,
        save_path,
        replay,
        plan: args.plan,
        antialias: args.antialias,
    };
    let (width, height) = args.window;
    let shared = shared.filter(|shared| match args.device {
        "shared" => true,
        "own" => false,
        // Measured on lavapipe (docs/app.md): sharing its one queue made strokes 5× slower.
        _ => !shared.software,
    });
    let sharing = if shared.is_some() {
        "the window draws with the engine's GPU device"
    } else {
        "the window opens its own GPU device"
    };
    eprintln!("slayer gui: {sharing}");
    slayer::app::run(setup, [width as f32, height as f32], shared).map_err(anyhow::Error::msg)?;
    Ok(ExitCode::SUCCESS)
}
