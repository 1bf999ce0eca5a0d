//! The `slayer` command line: generate scenes, check mesh files, run the demo.

mod backend;
mod bench;
mod check;
mod convert;
mod demo;
mod gui;
mod history;
mod layer;
mod open;
mod progress;
mod remesh;
mod render;
mod scene;
mod sculpt;
mod strokes;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Heap accounting for the figures `bench` and `sculpt --stats` report (bytes per face).
#[global_allocator]
static HEAP: slayer::memory::Counting = slayer::memory::Counting;

#[derive(Parser)]
#[command(
    name = "slayer",
    version,
    about = "Multi-layer material sculpting with collisions"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Refuse a mesh file that is not a clean manifold mesh (non-manifold, degenerate,
    /// duplicate or inconsistently oriented faces) instead of repairing it
    #[arg(long, global = true)]
    strict: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Sculpt and paint the generated default material with a seeded script; write, check, render
    Demo {
        /// Folder for the demo's files.
        #[arg(long, default_value = "slayer-demo")]
        out: PathBuf,
        /// Triangles in the generated material.
        #[arg(long, default_value_t = 640_000)]
        triangles: usize,
        /// auto (a hardware GPU if there is one, else the CPU), cpu, or gpu (any adapter,
        /// lavapipe included).
        #[arg(long, default_value = "auto", value_name = "auto|cpu|gpu")]
        backend: backend::Backend,
    },
    /// Write a generated scene: plane, sphere, plaster, bark or metal.
    Scene {
        /// Scene name: plane, sphere, plaster, bark, metal.
        name: String,
        /// Target triangle count (the result lands within ±5 %); defaults to the scene's size.
        #[arg(long)]
        triangles: Option<usize>,
        /// Random seed: the same arguments always give a byte-identical file.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Displace interior vertices along the surface by up to this many edge lengths (0 to
        /// 0.4): a deliberately irregular mesh, e.g. to try `slayer remesh` on.
        #[arg(long, default_value_t = 0.0)]
        jitter: f32,
        /// Output file: a mesh (.obj, .ply, .stl, .glb, .gltf) or a session (.slayer).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Report a mesh file's figures and defects; exits non-zero on any defect.
    Check {
        file: PathBuf,
        /// Print one JSON object instead of the table.
        #[arg(long)]
        json: bool,
        /// The file FILE was made from: report each closed component's volume change, and a
        /// change over 5 % as a defect.
        #[arg(long, value_name = "ORIGINAL")]
        against: Option<PathBuf>,
    },
    /// Convert a mesh or session between formats by extension (.obj, .ply, .stl, .glb, .gltf,
    /// .slayer), repairing it on the way unless --strict
    Convert {
        /// Mesh (.obj, .ply, .stl, .glb, .gltf) or session (.slayer).
        input: PathBuf,
        /// Mesh (.obj with its .mtl, .ply, .stl, .glb, .gltf) or session (.slayer).
        output: PathBuf,
        /// Keep only these layers (names or numbers, comma-separated), in this order.
        #[arg(long, value_delimiter = ',')]
        layers: Vec<String>,
    },
    /// Apply a stroke file to a mesh or session and write the result (the input is never
    /// modified unless `--in-place` is given). A `.slayer` output keeps every stroke as an
    /// undoable history entry.
    Sculpt {
        /// Mesh (.obj, .ply, .stl, .glb, .gltf) or session (.slayer).
        #[arg(long)]
        input: PathBuf,
        /// Stroke file (JSON; see `slayer::brush` docs or README).
        #[arg(long)]
        strokes: PathBuf,
        /// Mesh (.obj, .ply, .stl, .glb, .gltf) or session (.slayer, with the history).
        #[arg(short, long)]
        output: PathBuf,
        /// Allow the output to be the input file itself (it is replaced only once the whole
        /// result is written).
        #[arg(long)]
        in_place: bool,
        /// The most dabs (samples after resampling at the stroke's spacing) one stroke may make.
        #[arg(long, default_value_t = slayer::brush::MAX_DABS_PER_STROKE, value_name = "N")]
        max_dabs: usize,
        /// The most faces one stroke's remeshing may create (or as many as the mesh has, where
        /// that is more); past it, long edges are left unsplit and `sculpt` warns.
        #[arg(long, default_value_t = slayer::pipeline::NEW_FACES_PER_STROKE, value_name = "N")]
        max_new_faces: usize,
        /// The longest, in edge lengths, a stroke may stretch an edge before remeshing refines
        /// it (or the mesh's longest edge, where that is more); the step that stretches one
        /// past it is the stroke's last, what it did is kept, and `sculpt` warns.
        #[arg(long, default_value_t = slayer::pipeline::MAX_STRETCH, value_name = "L")]
        max_stretch: f32,
        /// The edge length `L` the strokes work at (collision distance, step, remeshing
        /// target), in world units; by default the mesh's mean edge length before the first
        /// stroke. Give the one a session ran at to replay its strokes as they ran.
        #[arg(long, value_name = "L")]
        edge_length: Option<f32>,
        /// Write per-stroke phase timings and counts as JSON.
        #[arg(long)]
        stats: Option<PathBuf>,
        /// Mirror every stroke that names no `symmetry` of its own across the plane through the
        /// mesh's centre across this axis.
        #[arg(long, value_name = "x|y|z", value_parser = ["x", "y", "z"])]
        symmetry: Option<String>,
        /// Remesh the touched region: after every stroke, after every stroke sample, or off.
        #[arg(long, default_value = "stroke", value_name = "stroke|sample|off")]
        remesh: slayer::pipeline::Remeshing,
        /// auto (a hardware GPU if there is one, else the CPU), cpu, or gpu (any adapter,
        /// lavapipe included).
        #[arg(long, default_value = "auto", value_name = "auto|cpu|gpu")]
        backend: backend::Backend,
        /// Test every vertex against everything near it, even where the layer is a sheet that
        /// cannot touch itself or no other layer is near: the same result, slower; to compare.
        #[arg(long)]
        no_cull: bool,
        /// How a layer meets itself: `collide` (contact stops motion) or `fuse` (parts that
        /// touch join, necks thinner than the join distance split). `fuse` alone sets every
        /// layer; `LAYER=fuse` one layer, by index or name. Repeat for several.
        #[arg(long, value_name = "[LAYER=]collide|fuse")]
        policy: Vec<String>,
    },
    /// Undo the last entries of a session file's history and write the result.
    Undo {
        /// Session file (.slayer).
        session: PathBuf,
        /// How many entries to undo.
        #[arg(long, default_value_t = 1)]
        steps: usize,
        /// Output: a session (.slayer, the undone entries kept for redo) or a mesh.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Redo the first undone entries of a session file's history and write the result.
    Redo {
        /// Session file (.slayer).
        session: PathBuf,
        /// How many entries to redo.
        #[arg(long, default_value_t = 1)]
        steps: usize,
        /// Output: a session (.slayer) or a mesh.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// List a session file's history: each entry and the bytes it holds.
    History {
        /// Session file (.slayer).
        session: PathBuf,
        #[arg(long)]
        json: bool,
    },
    /// Remesh a whole mesh toward a uniform edge length (split, collapse, flip, relax; whole
    /// levels of subdivision first when refining by a large factor), and report the result's
    /// quality and its distance to the input.
    Remesh {
        file: PathBuf,
        /// Target edge length; the mesh's mean edge length by default.
        #[arg(long, conflicts_with_all = ["faces", "scale"])]
        edge: Option<f32>,
        /// Target face count: the edge length whose equilateral triangles cover the mesh's
        /// area this many times.
        #[arg(long, conflicts_with = "scale")]
        faces: Option<u64>,
        /// Target edge length as a multiple of the mean edge: 0.5 halves the edges (about 4×
        /// the faces), 2 doubles them.
        #[arg(long)]
        scale: Option<f32>,
        /// Print one JSON object (the quality before and after, the distance to the input, what
        /// the remesh did) instead of the lines.
        #[arg(long)]
        json: bool,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Write the bench's seeded stroke script for a scene.
    Strokes {
        #[arg(long, default_value = "plaster")]
        scene: String,
        #[arg(long)]
        triangles: Option<usize>,
        #[arg(long, default_value_t = 40)]
        count: usize,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Every brush, pushed harder (the property tests' mix).
        #[arg(long)]
        torture: bool,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Time the brush pipeline on generated scenes, in the layout of the sLayer paper's Table 1.
    Bench {
        /// plaster, bark, metal (the paper's materials), plane (straight draw strokes), sphere
        /// (inflate and grab), or all (the three materials).
        #[arg(long, default_value = "all")]
        scene: String,
        #[arg(long)]
        triangles: Option<usize>,
        #[arg(long, default_value_t = 40)]
        strokes: usize,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Write the figures as JSON (the fields of docs/bench.md).
        #[arg(long)]
        json: Option<PathBuf>,
        /// Also run the same strokes on plaster from 250K to 16M faces, with the peak heap per face (about 4 GB of memory at 16M).
        #[arg(long)]
        scaling: bool,
        /// Face counts for --scaling.
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "250000,1000000,4000000,16000000"
        )]
        scaling_sizes: Vec<usize>,
        /// cpu; gpu (the GPU's selection, deformation and proximity passes, any adapter including lavapipe);
        /// auto (a hardware GPU if there is one, else the CPU); both (the same strokes on each,
        /// compared).
        #[arg(long, default_value = "cpu", value_name = "cpu|gpu|auto|both")]
        backend: backend::Backend,
        /// Remesh the touched region: after every stroke, after every stroke sample, or off.
        #[arg(long, default_value = "stroke", value_name = "stroke|sample|off")]
        remesh: slayer::pipeline::Remeshing,
        /// Feed each stroke this many samples per call, as an app does pointer event by
        /// pointer event (default: the whole stroke in one call, the batch).
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
        samples_per_call: Option<u64>,
        /// Test every vertex against everything near it, even where the layer is a sheet that
        /// cannot touch itself or no other layer is near: the same result, slower; to compare.
        #[arg(long)]
        no_cull: bool,
        /// How each brushed layer meets itself: `collide` or `fuse` (parts that touch join;
        /// the report adds the joins, splits and their share of the time).
        #[arg(long, default_value = "collide", value_name = "collide|fuse")]
        policy: slayer::topology::ProximityPolicy,
    },
    /// Render a mesh file to a PNG with the preview renderer (headless; lavapipe without a GPU).
    ///
    /// Each vertex's BRDF is shaded with a microfacet model (Blinn-Phong distribution, Fresnel,
    /// shadowing) under a key and a fill light. The camera orbits the mesh's bounding box with
    /// +z up and frames it whole.
    Render {
        /// Mesh or session file (.ply and .slayer keep painted BRDFs, .obj its materials per layer,
        /// .stl renders in clay).
        file: PathBuf,
        /// Output PNG.
        #[arg(short, long)]
        output: PathBuf,
        /// Image size, WIDTHxHEIGHT (`1920x1080` or `1920×1080`); at most the adapter's largest
        /// texture and 8192² pixels.
        #[arg(long, default_value = "1280x960", value_parser = render::parse_size)]
        size: (u32, u32),
        /// `AZIMUTH,ELEVATION[,DISTANCE]`: degrees around +z (0 looks from -y), degrees above
        /// the xy plane (90 looks straight down), and a multiple of the distance that fits the
        /// whole mesh (0.5 zooms in twice).
        #[arg(long, default_value = "-30,50", value_parser = render::parse_camera, allow_hyphen_values = true)]
        camera: slayer::render::CameraSpec,
        /// Draw only these layers, by index or name: `--layers 0,2` or `--layers paint`.
        #[arg(long, value_delimiter = ',')]
        layers: Vec<String>,
        /// Show each layer in its own colour instead of its painted material.
        #[arg(long, alias = "false-color")]
        false_colour: bool,
        /// Overlay the triangle edges.
        #[arg(long)]
        wireframe: bool,
        /// Turn off 4x multisampling.
        #[arg(long)]
        no_antialias: bool,
        /// Which axis of the file points up: `y` (most modelling tools' OBJ and PLY), `z`
        /// (slayer's own files, STL, glTF after import), or `auto` to guess from the file.
        #[arg(long, default_value = "auto", value_parser = ["auto", "y", "z"])]
        up: String,
    },
    /// Sculpt by hand: the app, in a window (OBJ, PLY, STL, glTF or .slayer; no file: the
    /// default plaster).
    ///
    /// The headless hooks play a stroke file through the same path as the mouse, then save,
    /// take a screenshot of the window and quit: `slayer gui --replay s.json --screenshot
    /// out.png --exit-after-frames 5`.
    Gui {
        file: Option<PathBuf>,
        /// Triangles of the default plaster (no FILE).
        #[arg(long, default_value_t = 200_000)]
        triangles: usize,
        /// Stroke file to play through the pointer's path before the app is yours.
        #[arg(long)]
        replay: Option<PathBuf>,
        /// After the replay, save the session here (.slayer keeps the history).
        #[arg(long)]
        save: Option<PathBuf>,
        /// After the replay, turn the camera this many frames (a degree each).
        #[arg(long, default_value_t = 0)]
        spin_frames: u32,
        /// After the replay (and spin), quit this many frames later.
        #[arg(long)]
        exit_after_frames: Option<u32>,
        /// Write the window's pixels as PNG just before quitting (needs --exit-after-frames).
        #[arg(long, requires = "exit_after_frames")]
        screenshot: Option<PathBuf>,
        /// Write frame rates, pointer-to-frame latency, uploads and peak memory (JSON) on exit.
        #[arg(long)]
        metrics: Option<PathBuf>,
        /// Window size, WIDTHxHEIGHT.
        #[arg(long, default_value = "1280x800", value_parser = render::parse_size)]
        window: (u32, u32),
        /// Draw the viewport without 4x multisampling (twice the frame rate on a software
        /// rasterizer such as lavapipe).
        #[arg(long)]
        no_antialias: bool,
        /// auto (a hardware GPU if there is one, else the CPU), cpu, or gpu (any adapter,
        /// lavapipe included).
        #[arg(long, default_value = "auto", value_name = "auto|cpu|gpu")]
        backend: backend::Backend,
        /// With the GPU backend, which device the window draws with: the engine's (`shared`),
        /// its own (`own`), or `auto`: shared on a hardware GPU, its own on a software one
        /// (lavapipe's single queue would hold the engine's read-backs behind each frame).
        #[arg(long, default_value = "auto", value_parser = ["auto", "shared", "own"])]
        device: String,
    },
    /// Layer tools: list the layers and their components, duplicate (offset copy or shell),
    /// delete.
    #[command(subcommand)]
    Layer(layer::LayerCommand),
    /// List the GPU adapters wgpu can see, best first.
    Adapters {
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    restore_sigpipe();
    let cli = Cli::parse();
    // Where the user asked for JSON, a failure is JSON too.
    let json_errors = matches!(
        cli.command,
        Command::Check { json: true, .. }
            | Command::Adapters { json: true }
            | Command::Layer(layer::LayerCommand::List { json: true, .. })
    );
    match dispatch(cli.command, cli.strict) {
        Ok(code) => code,
        Err(error) => {
            let line = one_line(&error);
            eprintln!("error: {line}");
            if json_errors {
                println!("{}", serde_json::json!({ "error": line }));
            }
            ExitCode::FAILURE
        }
    }
}

/// Runs a subcommand. A table more than a function: one arm per subcommand, each handing its
/// arguments on, so it is as long as the list of subcommands.
fn dispatch(command: Command, strict: bool) -> anyhow::Result<ExitCode> {
    match command {
        Command::Demo {
            out,
            triangles,
            backend,
        } => demo::run(&out, triangles, backend),
        Command::Scene {
            name,
            triangles,
            seed,
            jitter,
            output,
        } => scene::run(&name, triangles, seed, jitter, &output),
        Command::Check {
            file,
            json,
            against,
        } => check::run(&file, json, against.as_deref(), strict),
        Command::Adapters { json } => adapters(json),
        Command::Layer(command) => layer::run(command, strict),
        Command::Convert {
            input,
            output,
            layers,
        } => convert::run(&input, &output, &layers, strict),
        Command::Sculpt {
            input,
            strokes,
            output,
            in_place,
            max_dabs,
            max_new_faces,
            max_stretch,
            edge_length,
            stats,
            symmetry,
            remesh,
            backend,
            no_cull,
            policy,
        } => sculpt::run(&sculpt::Args {
            input: &input,
            strokes: &strokes,
            output: &output,
            in_place,
            max_dabs,
            max_new_faces,
            max_stretch,
            edge_length,
            stats: stats.as_deref(),
            symmetry: symmetry.as_deref(),
            remeshing: remesh,
            backend,
            strict,
            cull: !no_cull,
            policies: &policy,
        }),
        Command::Remesh {
            file,
            edge,
            faces,
            scale,
            json,
            output,
        } => {
            let target = match (edge, faces, scale) {
                (Some(edge), _, _) => remesh::Target::Edge(edge),
                (_, Some(faces), _) => remesh::Target::Faces(faces),
                (_, _, Some(scale)) => remesh::Target::Scale(scale),
                _ => remesh::Target::MeanEdge,
            };
            remesh::run(&file, target, (&output, json), strict)
        }
        Command::Undo {
            session,
            steps,
            output,
        } => history::step(&session, history::Step::Undo, steps, &output),
        Command::Redo {
            session,
            steps,
            output,
        } => history::step(&session, history::Step::Redo, steps, &output),
        Command::History { session, json } => history::list(&session, json),
        Command::Render {
            file,
            output,
            size,
            camera,
            layers,
            false_colour,
            wireframe,
            no_antialias,
            up,
        } => render::run(&render::Args {
            file: &file,
            output: &output,
            size,
            camera,
            layers: &layers,
            false_colour,
            wireframe,
            antialias: !no_antialias,
            up: &up,
            strict,
        }),
        Command::Gui {
            file,
            triangles,
            replay,
            save,
            spin_frames,
            exit_after_frames,
            screenshot,
            metrics,
            window,
            no_antialias,
            backend,
            device,
        } => gui::run(gui::Args {
            file: file.as_deref(),
            triangles,
            replay: replay.as_deref(),
            plan: slayer::app::ExitPlan {
                save,
                spin_frames,
                exit_after_frames,
                screenshot,
                metrics,
            },
            window,
            antialias: !no_antialias,
            backend,
            device: &device,
            strict,
        }),
        Command::Strokes {
            scene,
            triangles,
            count,
            seed,
            torture,
            output,
        } => strokes::run(&scene, triangles, count, seed, torture, &output),
        Command::Bench {
            scene,
            triangles,
            strokes,
            seed,
            json,
            scaling,
            scaling_sizes,
            backend,
            remesh,
            samples_per_call,
            no_cull,
            policy,
        } => {
            let scenes = match bench::parse_scenes(&scene) {
                Ok(scenes) => scenes,
                Err(e) => {
                    eprintln!("error: {e}");
                    return Ok(ExitCode::FAILURE);
                }
            };
            bench::run(&bench::Options {
                scenes,
                triangles,
                strokes,
                seed,
                json,
                scaling,
                scaling_sizes,
                backend,
                remeshing: remesh,
                samples_per_call: samples_per_call.map(|n| n as usize),
                cull: !no_cull,
                policy,
            })
        }
    }
}

/// A closed stdout (`slayer check FILE | head -1`) ends the program quietly, as it does any
/// Unix tool, instead of a panic in the next `println!`: Rust ignores SIGPIPE by default.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: run first thing in main, before any thread starts; resetting a signal's
    // disposition to its default touches no memory of ours.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// An error and its causes on one line.
pub fn one_line(error: &anyhow::Error) -> String {
    // The chain, outermost first; a cause whose text its wrapper already quotes is not repeated
    // (an I/O error inside "FILE: <io error>" would otherwise print twice).
    let mut line = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if !line.contains(&text) {
            if !line.is_empty() {
                line.push_str(": ");
            }
            line.push_str(&text);
        }
    }
    // Messages may quote a file's bytes: no control character reaches the terminal.
    slayer::files::escape(&line.replace('\n', " ")).into_owned()
}

fn adapters(json: bool) -> anyhow::Result<ExitCode> {
    let adapters = slayer::gpu::list_adapters();
    if json {
        println!("{}", serde_json::to_string_pretty(&adapters)?);
    } else if adapters.is_empty() {
        println!("no GPU adapters (the CPU backend will be used)");
    } else {
        for a in &adapters {
            println!("{a}{}", if a.software { "  [software]" } else { "" });
        }
    }
    Ok(ExitCode::SUCCESS)
}
