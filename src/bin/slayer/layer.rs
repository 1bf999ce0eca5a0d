//! `slayer layer list|duplicate|delete`: the layer tools from the command line. A tool that
//! fails writes nothing; a `.slayer` output keeps it (and any mask strokes) as history entries.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use slayer::mesh::LayerId;
use slayer::pipeline::{Pipeline, PipelineSettings};
use slayer::session::Session;
use slayer::tools::{DeleteTarget, DuplicateSettings, Selection};

#[derive(Subcommand)]
pub enum LayerCommand {
    /// Print each layer with its faces and its connected components (the numbers that
    /// `--component` takes).
    List {
        /// Mesh or session file.
        file: PathBuf,
        #[arg(long)]
        json: bool,
    },
    /// Copy a layer, its masked part or a component into a new layer lifted off it along the
    /// normals, clear of everything (a flake above the plaster, a second skin of bark).
    Duplicate {
        #[command(flatten)]
        files: Files,
        /// The layer to copy (name or number); with --masked only its masked part.
        #[arg(long, conflicts_with = "component")]
        layer: Option<String>,
        /// The connected component to copy (numbered as `slayer layer list` prints them).
        #[arg(long)]
        component: Option<u32>,
        /// Copy only the layer's masked faces (all three vertices masked).
        #[arg(long, requires = "layer")]
        masked: bool,
        /// A stroke file applied first (mask strokes, typically), to mask what --masked copies.
        #[arg(long, value_name = "FILE", requires = "masked")]
        mask_strokes: Option<PathBuf>,
        /// The new layer (its name defaults to the source's with " copy", its material to
        /// the source layer's).
        #[command(flatten)]
        lift: Lift,
    },
    /// Make a new layer of the Coons patch that fills each closed stroke of a stroke file
    /// (its samples the outline, drawn on --layer), lifted off the surface like a duplicate.
    Patch {
        #[command(flatten)]
        files: Files,
        /// Stroke file whose strokes outline the patches (each closed: it ends where it began).
        #[arg(long, value_name = "FILE")]
        strokes: PathBuf,
        /// The layer the outlines are drawn on (name or number).
        #[arg(long)]
        layer: String,
        /// The new layer (named `patch`, in `paint` unless told).
        #[command(flatten)]
        lift: Lift,
    },
    /// Cut layers open along the strokes of a stroke file (each stroke one cut, its samples
    /// the path): snapped to the edges, opened by the collision distance. A closed or
    /// rim-to-rim cut detaches a piece, an open one makes a slit.
    Cut {
        #[command(flatten)]
        files: Files,
        /// Stroke file whose samples trace the cuts.
        #[arg(long, value_name = "FILE")]
        strokes: PathBuf,
        /// The layers to cut (names or numbers, comma-separated); default: every layer.
        #[arg(long, value_delimiter = ',')]
        layers: Vec<String>,
    },
    /// Delete a layer or connected components, and compact the mesh.
    Delete {
        #[command(flatten)]
        files: Files,
        /// A whole layer (name or number); the layers after it move down by one.
        #[arg(long, group = "target")]
        layer: Option<String>,
        /// One component (numbered as `slayer layer list` prints them).
        #[arg(long, group = "target")]
        component: Option<u32>,
        /// The N components with the fewest faces.
        #[arg(long, group = "target", value_name = "N")]
        smallest: Option<usize>,
        /// Every component with fewer faces than this.
        #[arg(long, group = "target", value_name = "FACES")]
        under: Option<usize>,
    },
}

/// The new layer a duplicate or a patch makes.
#[derive(Args)]
pub struct Lift {
    /// How far it is lifted off the surface, in mean edge lengths (the collision distance is 1).
    #[arg(long, default_value_t = 2.0)]
    offset: f32,
    /// Make a closed shell this thick (in mean edge lengths) instead of a sheet.
    #[arg(long)]
    thickness: Option<f32>,
    /// The new layer's name.
    #[arg(long)]
    name: Option<String>,
    /// The new layer's material: a preset name (plaster, paint, rust, ...).
    #[arg(long)]
    material: Option<String>,
}

impl Lift {
    /// The tool's settings in world units, from edge lengths and names; `defaults` are the
    /// name and material where none was given.
    fn settings(
        &self,
        mesh: &slayer::mesh::Mesh,
        (name, material): (String, slayer::mesh::Brdf),
    ) -> anyhow::Result<DuplicateSettings> {
        let material = match &self.material {
            Some(preset) => {
                slayer::material::preset(preset)
                    .with_context(|| format!("--material: no preset `{preset}`"))?
                    .brdf
            }
            None => material,
        };
        let name = self.name.clone().unwrap_or(name);
        let mut settings = DuplicateSettings::for_mesh(mesh, &name, material);
        settings.offset = self.offset * settings.edge;
        settings.thickness = self.thickness.map(|t| t * settings.edge);
        Ok(settings)
    }
}

/// The input and output of a tool.
#[derive(Args)]
pub struct Files {
    /// Mesh (.obj, .ply, .stl, .glb, .gltf) or session (.slayer).
    input: PathBuf,
    /// Mesh or session (.slayer, which keeps the tool as an undoable history entry).
    #[arg(short, long)]
    output: PathBuf,
    /// Allow the output to be the input file itself.
    #[arg(long)]
    in_place: bool,
}

pub fn run(command: LayerCommand, strict: bool) -> anyhow::Result<ExitCode> {
    match command {
        LayerCommand::List { file, json } => list(&file, json, strict),
        LayerCommand::Duplicate {
            files,
            layer,
            component,
            masked,
            mask_strokes,
            lift,
        } => {
            let mut session = open(&files, strict)?;
            let selection = match (layer, component) {
                (Some(layer), _) => {
                    let layer = one_layer(session.mesh(), &layer)?;
                    if masked {
                        Selection::Masked(layer)
                    } else {
                        Selection::Layer(layer)
                    }
                }
                (None, Some(component)) => Selection::Component(component),
                (None, None) => bail!("say what to copy: --layer or --component"),
            };
            if let Some(strokes) = &mask_strokes {
                apply_strokes(&mut session, strokes)?;
            }
            let source = source_layer(session.mesh(), selection)?;
            let defaults = (
                format!("{} copy", session.mesh().layer_names()[source as usize]),
                session.layers()[source as usize].material,
            );
            let settings = lift.settings(session.mesh(), defaults)?;
            let (report, _) = session.duplicate(selection, &settings)?;
            save(&session, &files)?;
            println!(
                "new layer {} `{}`: {} faces, lifted {:.3} ({} vertices stopped short by what is in the way), {:.0} ms -> {}",
                report.layer,
                settings.name,
                report.faces,
                report.smallest_lift,
                report.clamped,
                report.millis,
                files.output.display()
            );
            Ok(ExitCode::SUCCESS)
        }
        LayerCommand::Cut {
            files,
            strokes,
            layers,
        } => cut(&files, &strokes, &layers, strict),
        LayerCommand::Patch {
            files,
            strokes,
            layer,
            lift,
        } => {
            let mut session = open(&files, strict)?;
            let layer = one_layer(session.mesh(), &layer)?;
            let defaults = ("patch".to_string(), slayer::material::PAINT.brdf);
            let settings = lift.settings(session.mesh(), defaults)?;
            for (i, outline) in stroke_paths(&session, &strokes)?.iter().enumerate() {
                let (report, _) = session
                    .patch(outline, layer, &settings)
                    .with_context(|| format!("{}: strokes[{i}]", strokes.display()))?;
                println!(
                    "patch {i}: new layer {} `{}`, {} faces, lifted {:.3} ({} vertices stopped short), {:.0} ms",
                    report.layer,
                    settings.name,
                    report.faces,
                    report.smallest_lift,
                    report.clamped,
                    report.millis
                );
            }
            save(&session, &files)?;
            println!("-> {}", files.output.display());
            Ok(ExitCode::SUCCESS)
        }
        LayerCommand::Delete {
            files,
            layer,
            component,
            smallest,
            under,
        } => {
            let mut session = open(&files, strict)?;
            let target = match (layer, component, smallest, under) {
                (Some(layer), ..) => DeleteTarget::Layer(one_layer(session.mesh(), &layer)?),
                (_, Some(c), ..) => DeleteTarget::Component(c),
                (_, _, Some(n), _) => DeleteTarget::Smallest(n),
                (_, _, _, Some(faces)) => DeleteTarget::Under(faces),
                _ => bail!("say what to delete: --layer, --component, --smallest or --under"),
            };
            let (deleted, _) = session.delete(target)?;
            save(&session, &files)?;
            println!(
                "deleted {} components ({} faces){}, {:.0} ms -> {}",
                deleted.components,
                deleted.faces,
                deleted
                    .layer
                    .map(|l| format!(", layer {l}"))
                    .unwrap_or_default(),
                deleted.millis,
                files.output.display()
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}

fn cut(files: &Files, strokes: &Path, layers: &[String], strict: bool) -> anyhow::Result<ExitCode> {
    let mut session = open(files, strict)?;
    let mesh = session.mesh();
    let layers = if layers.is_empty() {
        (0..mesh.layer_count() as LayerId).collect()
    } else {
        crate::render::resolve_layers(mesh, layers)?
    };
    let settings = slayer::tools::CutSettings::for_mesh(mesh, &layers);
    let name = strokes.display().to_string();
    for (i, path) in stroke_paths(&session, strokes)?.iter().enumerate() {
        let (report, _) = session
            .cut(path, &settings)
            .with_context(|| format!("{name}: strokes[{i}]"))?;
        println!(
            "cut {}: {} edges ({} split to follow the stroke, within {:.2} edges of it), {} vertices duplicated, components {} -> {}, {:.0} ms",
            i,
            report.path_edges,
            report.splits,
            report.farthest_from_stroke / settings.edge,
            report.duplicated,
            report.components_before,
            report.components_after,
            report.millis
        );
    }
    save(&session, files)?;
    println!("-> {}", files.output.display());
    Ok(ExitCode::SUCCESS)
}

/// Each stroke of a stroke file as the polyline of its samples.
fn stroke_paths(session: &Session, path: &Path) -> anyhow::Result<Vec<Vec<glam::Vec3>>> {
    let text = slayer::files::read_input_text(path, slayer::files::MAX_INPUT_BYTES)
        .with_context(|| format!("{}", path.display()))?;
    let name = path.display().to_string();
    let file = slayer::brush::StrokeFile::parse(&text, &name)?;
    let strokes = file.resolve(session.mesh(), &name)?;
    Ok(strokes
        .iter()
        .map(|s| s.samples.iter().map(|s| s.position).collect())
        .collect())
}

fn list(file: &Path, json: bool, strict: bool) -> anyhow::Result<ExitCode> {
    let session = crate::open::open_without_history(file, strict)?;
    let summaries = slayer::tools::layer_summaries(session.mesh());
    if json {
        println!("{}", serde_json::to_string_pretty(&summaries)?);
        return Ok(ExitCode::SUCCESS);
    }
    for layer in &summaries {
        println!(
            "layer {} `{}`: {} faces, {} vertices, {} components",
            layer.layer,
            slayer::files::escape(&layer.name),
            layer.faces,
            layer.vertices,
            layer.components.len()
        );
        for c in &layer.components {
            let closed = if c.closed { "closed" } else { "open" };
            println!("  component {}: {} faces, {closed}", c.component, c.faces);
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Opens the input, refusing an output that is the input without `--in-place`; a mesh output
/// needs no history.
fn open(files: &Files, strict: bool) -> anyhow::Result<Session> {
    slayer::session::check_save_path(&files.output)?;
    if !files.in_place && crate::sculpt::same_file(&files.input, &files.output) {
        bail!(
            "{}: the output is the input file; give another --output, or --in-place to replace \
             the input",
            files.output.display()
        );
    }
    if slayer::session::is_session_path(&files.output) {
        crate::open::open(&files.input, strict)
    } else {
        crate::open::open_without_history(&files.input, strict)
    }
}

fn save(session: &Session, files: &Files) -> anyhow::Result<()> {
    session
        .mesh()
        .validate()
        .context("the result failed validation (not written)")?;
    slayer::session::save(session, &files.output, true)
        .with_context(|| format!("writing {}", files.output.display()))
}

fn one_layer(mesh: &slayer::mesh::Mesh, name: &str) -> anyhow::Result<LayerId> {
    Ok(crate::render::resolve_layers(mesh, &[name.to_string()])?[0])
}

/// Applies a stroke file's strokes (on the CPU) as history entries.
fn apply_strokes(session: &mut Session, path: &Path) -> anyhow::Result<()> {
    let text = slayer::files::read_input_text(path, slayer::files::MAX_INPUT_BYTES)
        .with_context(|| format!("{}", path.display()))?;
    let name = path.display().to_string();
    let file = slayer::brush::StrokeFile::parse(&text, &name)?;
    let strokes = file.resolve(session.mesh(), &name)?;
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    for (i, stroke) in strokes.iter().enumerate() {
        session
            .apply_stroke(&mut pipeline, stroke)
            .with_context(|| format!("{name}: strokes[{i}]"))?;
    }
    Ok(())
}

/// The layer a selection lies on.
fn source_layer(mesh: &slayer::mesh::Mesh, selection: Selection) -> anyhow::Result<LayerId> {
    let faces = slayer::tools::selected_faces(mesh, selection)?;
    Ok(mesh.face_layers()[faces[0] as usize])
}
