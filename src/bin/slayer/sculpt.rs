use std::path::Path;
use std::process::ExitCode;

use anyhow::{Context, bail};
use slayer::brush::{Stroke, StrokeFile, SymmetrySpec, dabs_for};
use slayer::io::AtomicBatch;
use slayer::pipeline::step::MAX_STEPS_PER_SAMPLE;
use slayer::pipeline::{PipelineSettings, Remeshing, StrokeReport};
use slayer::session::{LayerSettings, ProximityPolicy, Session};

use crate::progress::Bar;

/// What `slayer sculpt` was given.
pub struct Args<'a> {
    pub input: &'a Path,
    pub strokes: &'a Path,
    pub output: &'a Path,
    /// The output may be the input file itself.
    pub in_place: bool,
    /// The most dabs one stroke may make.
    pub max_dabs: usize,
    pub max_new_faces: usize,
    /// Edge lengths a stroke may stretch an edge to (`PipelineSettings::max_stretch`).
    pub max_stretch: f32,
    /// The pipeline's edge length `L`, when given (else the mesh's mean edge length).
    pub edge_length: Option<f32>,
    pub stats: Option<&'a Path>,
    /// `x`, `y` or `z`: the mirror of strokes that name none.
    pub symmetry: Option<&'a str>,
    pub remeshing: Remeshing,
    pub backend: crate::backend::Backend,
    /// Refuse an input mesh that needs repairs.
    pub strict: bool,
    /// Skip the collision searches that cannot find anything (`--no-cull`: off).
    pub cull: bool,
    /// `--policy` values: `collide|fuse` for every layer, `LAYER=collide|fuse` for one.
    pub policies: &'a [String],
}

/// Sets the layers' proximity policies as `--policy` says (each is a history entry).
pub fn set_policies(session: &mut Session, specs: &[String]) -> anyhow::Result<()> {
    for spec in specs {
        let (layer, policy) = match spec.split_once('=') {
            Some((layer, policy)) => (Some(layer), policy),
            None => (None, spec.as_str()),
        };
        let policy: ProximityPolicy = policy
            .parse()
            .map_err(|e| anyhow::anyhow!("--policy {spec}: {e}"))?;
        let layers: Vec<u32> = match layer {
            None => (0..session.mesh().layer_count() as u32).collect(),
            Some(name) => {
                vec![find_layer(session.mesh(), name).with_context(|| format!("--policy {spec}"))?]
            }
        };
        for l in layers {
            let settings = LayerSettings {
                policy,
                ..session.layers()[l as usize]
            };
            session.set_layer(l, settings)?;
        }
    }
    Ok(())
}

/// A layer by index or name.
fn find_layer(mesh: &slayer::mesh::Mesh, name: &str) -> anyhow::Result<u32> {
    let names = mesh.layer_names();
    if let Some(l) = names.iter().position(|n| n == name) {
        return Ok(l as u32);
    }
    match name.parse::<u32>() {
        Ok(l) if (l as usize) < names.len() => Ok(l),
        _ => bail!(
            "no layer `{}` (the mesh has {})",
            slayer::files::escape(name),
            names.join(", ")
        ),
    }
}

/// Applies a stroke file to a mesh or session and writes the result (and the stats) as one
/// unit; the input is never touched unless `--in-place` names it as the output. Each stroke is
/// one history entry of the session a `.slayer` output keeps.
pub fn run(args: &Args<'_>) -> anyhow::Result<ExitCode> {
    check_lengths(args)?;
    slayer::session::check_save_path(args.output)?;
    refuse_overwriting_input(args)?;
    // A mesh file keeps no history: the session need not keep a copy of the mesh to undo to.
    let mut session = if slayer::session::is_session_path(args.output) {
        crate::open::open(args.input, args.strict)?
    } else {
        crate::open::open_without_history(args.input, args.strict)?
    };
    let text = slayer::files::read_input_text(args.strokes, slayer::files::MAX_INPUT_BYTES)
        .with_context(|| format!("{}", args.strokes.display()))?;
    let name = args.strokes.display().to_string();
    let mut file = StrokeFile::parse(&text, &name)?;
    if let Some(axis) = args.symmetry {
        for stroke in file.strokes.iter_mut().filter(|s| s.symmetry.is_none()) {
            stroke.symmetry = Some(SymmetrySpec::Axis(axis.to_string()));
        }
    }
    set_policies(&mut session, args.policies)?;
    for layer in file.fuse_layers(session.mesh(), &name)? {
        let settings = LayerSettings {
            policy: ProximityPolicy::Fuse,
            ..session.layers()[layer as usize]
        };
        session.set_layer(layer, settings)?;
    }
    let strokes = file.resolve(session.mesh(), &name)?;
    let load_peak = slayer::memory::peak_bytes();
    slayer::memory::reset_peak();
    check_dabs(&strokes, args.max_dabs, &name)?;
    let mut pipeline = crate::backend::choose(
        args.backend,
        PipelineSettings {
            remeshing: args.remeshing,
            max_dabs_per_stroke: args.max_dabs,
            new_faces_per_stroke: args.max_new_faces,
            max_stretch: args.max_stretch,
            edge_length: args.edge_length,
            cull: args.cull,
            ..PipelineSettings::default()
        },
    )?
    .pipeline;
    // What is proportional to the mesh (the grid, per-vertex scratch) is built here, once,
    // and reported as set-up: a stroke's cost follows the brush.
    let started = std::time::Instant::now();
    pipeline
        .prepare(session.mesh())
        .with_context(|| format!("{}: preparing the mesh for sculpting", args.input.display()))?;
    let setup_ms = started.elapsed().as_secs_f64() * 1e3;
    let bar = Bar::new("sculpt", strokes.len() as u64);
    let mut reports: Vec<StrokeReport> = Vec::with_capacity(strokes.len());
    for (i, stroke) in strokes.iter().enumerate() {
        let (report, recorded) = session
            .apply_stroke(&mut pipeline, stroke)
            .with_context(|| format!("{name}: strokes[{i}]"))?;
        if recorded.dropped > 0 {
            bar.println(&format!(
                "note: the history passed its cap of {} MiB; its {} oldest entries were dropped",
                session.history().cap_bytes() >> 20,
                recorded.dropped
            ));
        }
        for warning in bounds_met(i, &report, args.max_stretch) {
            bar.println(&warning);
        }
        reports.push(report);
        bar.inc();
    }
    bar.finish();
    if let Some(why) = pipeline.kernel_failure() {
        eprintln!("warning: the GPU failed ({why}); the strokes finished on the CPU");
    }
    let backend = pipeline.name();
    let strokes_peak = slayer::memory::peak_bytes();
    // The grid and scratch are done with: their memory goes back before validating.
    drop(pipeline);
    let mesh = session.mesh();
    mesh.validate()
        .context("the sculpted mesh failed validation (not written)")?;
    let mut batch = AtomicBatch::new();
    slayer::session::stage(&mut batch, &session, args.output, true)?;
    // The whole run's peak: loading, strokes, checking and writing the output.
    let peak = [load_peak, slayer::memory::peak_bytes()]
        .into_iter()
        .flatten()
        .max();
    let faces = mesh.live_face_count();
    if let Some(path) = args.stats {
        let json = serde_json::json!({
            "backend": backend,
            "strokes": reports,
            "vertices": mesh.live_vertex_count(),
            "faces": faces,
            "setup_ms": setup_ms,
            "peak_heap_bytes": peak,
            "load_peak_heap_bytes": load_peak,
            "strokes_peak_heap_bytes": strokes_peak,
            "peak_bytes_per_face": peak.map(|p| p as f64 / faces.max(1) as f64),
        });
        batch.stage(path, serde_json::to_string_pretty(&json)?.as_bytes())?;
    }
    batch.commit()?;
    let samples: usize = reports.iter().map(|r| r.samples).sum();
    let clamped: usize = reports.iter().map(|r| r.clamped).sum();
    let total_ms: f64 = reports.iter().map(|r| r.phases.total()).sum();
    println!(
        "{} strokes, {samples} samples, {clamped} collisions, {:.3} ms per sample (set-up {setup_ms:.0} ms{}) -> {}",
        strokes.len(),
        total_ms / samples.max(1) as f64,
        peak.map(|p| format!(
            ", peak heap {} MiB, {:.0} bytes per face",
            p >> 20,
            p as f64 / faces.max(1) as f64
        ))
        .unwrap_or_default(),
        args.output.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// `--edge-length` positive, `--max-stretch` from 2 (remeshing itself leaves edges up to
/// 4/3 L) to 10⁶.
fn check_lengths(args: &Args<'_>) -> anyhow::Result<()> {
    if let Some(edge) = args.edge_length
        && !(edge.is_finite() && edge > 0.0)
    {
        bail!("--edge-length {edge}: the edge length must be a positive number of world units");
    }
    if !(2.0..=1e6).contains(&args.max_stretch) {
        bail!(
            "--max-stretch {}: the bound is a number of edge lengths from 2 to 1000000",
            args.max_stretch
        );
    }
    Ok(())
}

/// A warning for each bound stroke `i` met: samples cut short, the stroke stopped where it
/// stretched an edge past `max_stretch`, remeshing stopped at its new faces.
fn bounds_met(i: usize, report: &StrokeReport, max_stretch: f32) -> Vec<String> {
    let mut warnings = Vec::new();
    if report.capped_samples > 0 {
        warnings.push(format!(
            "warning: strokes[{i}]: {} samples moved farther than {MAX_STEPS_PER_SAMPLE} steps allow and were cut short (a runaway brush: lower its strength or radius)",
            report.capped_samples
        ));
    }
    if let Some(stretched) = report.stopped_stretched {
        warnings.push(format!(
            "warning: strokes[{i}]: stopped after {} of its samples, where it stretched an edge to {stretched:.1} edge lengths, past the bound of {max_stretch} (what it did is kept; a smaller radius or strength stretches less; raise the bound with --max-stretch)",
            report.samples
        ));
    }
    if report.remesh.growth_capped > 0 {
        warnings.push(format!(
            "warning: strokes[{i}]: remeshing stopped splitting at {} new faces, the bound for one stroke (edges were left long; raise it with --max-new-faces)",
            report.new_faces_bound
        ));
    }
    warnings
}

/// The output (or the stats) naming the input file itself is refused without `--in-place`.
fn refuse_overwriting_input(args: &Args<'_>) -> anyhow::Result<()> {
    if args.in_place {
        return Ok(());
    }
    let outputs = [Some(args.output), args.stats];
    for output in outputs.into_iter().flatten() {
        if same_file(args.input, output) {
            bail!(
                "{}: the output is the input file; give another --output, or --in-place to \
                 replace the input",
                output.display()
            );
        }
    }
    Ok(())
}

/// Whether `a` and `b` name one file: by device and inode when both exist (links and other
/// spellings of one path included), by canonical path otherwise.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(a), Ok(b)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return (a.dev(), a.ino()) == (b.dev(), b.ino());
        }
    }
    let canonical = |p: &Path| {
        let folder = p.parent().filter(|f| !f.as_os_str().is_empty());
        let folder = folder.unwrap_or(Path::new(".")).canonicalize().ok()?;
        Some(folder.join(p.file_name()?))
    };
    matches!((canonical(a), canonical(b)), (Some(x), Some(y)) if x == y)
}

/// Refuses, before any stroke runs, a stroke that would make more than `limit` dabs.
fn check_dabs(strokes: &[Stroke], limit: usize, name: &str) -> anyhow::Result<()> {
    for (i, stroke) in strokes.iter().enumerate() {
        let step = stroke.settings().resampling_step();
        let dabs = dabs_for(&stroke.samples, step);
        if dabs > limit as f64 {
            bail!(
                "{name}: strokes[{i}].samples: the stroke would make about {dabs:.0} dabs at a \
                 step of {step} world units, more than the {limit} allowed; raise --max-dabs \
                 or split the stroke"
            );
        }
    }
    Ok(())
}
