//! The `slayer` command line: generate scenes, check mesh files, run the demo.

mod bench;
mod check;
mod demo;
mod progress;
mod remesh;
mod scene;
mod sculpt;
mod strokes;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "slayer",
    version,
    about = "Multi-layer material sculpting with collisions"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Generate the default material, write it and check it (the sculpting demo grows from here).
    Demo {
        /// Folder for the demo's files.
        #[arg(long, default_value = "slayer-demo")]
        out: PathBuf,
        /// Triangles in the generated material.
        #[arg(long, default_value_t = 640_000)]
        triangles: usize,
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
        /// Output file (.obj or .ply).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Report a mesh file's figures and defects; exits non-zero on any defect.
    Check {
        file: PathBuf,
        /// Print one JSON object instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Apply a stroke file to a mesh and write the result (the input is never modified).
    Sculpt {
        #[arg(long)]
        input: PathBuf,
        /// Stroke file (JSON; see `slayer::brush` docs or README).
        #[arg(long)]
        strokes: PathBuf,
        #[arg(long)]
        output: PathBuf,
        /// Write per-stroke phase timings and counts as JSON.
        #[arg(long)]
        stats: Option<PathBuf>,
        /// Remesh the touched region: after every stroke, after every stroke sample, or off.
        #[arg(long, default_value = "stroke", value_name = "stroke|sample|off")]
        remesh: slayer::pipeline::Remeshing,
    },
    /// Remesh a whole mesh toward a uniform edge length (split, collapse, flip, relax).
    Remesh {
        file: PathBuf,
        /// Target edge length; the mesh's mean edge length by default.
        #[arg(long)]
        edge: Option<f32>,
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
        /// plaster, bark, metal, or all.
        #[arg(long, default_value = "all")]
        scene: String,
        #[arg(long)]
        triangles: Option<usize>,
        #[arg(long, default_value_t = 40)]
        strokes: usize,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Write the figures as JSON (BENCHMARK.md's field names).
        #[arg(long)]
        json: Option<PathBuf>,
        /// Also run the same strokes on plaster from 250K to 4M faces.
        #[arg(long)]
        scaling: bool,
        /// Face counts for --scaling.
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "250000,500000,1000000,2000000,4000000"
        )]
        scaling_sizes: Vec<usize>,
        #[arg(long, default_value = "cpu")]
        backend: String,
        /// Remesh the touched region: after every stroke, after every stroke sample, or off.
        #[arg(long, default_value = "stroke", value_name = "stroke|sample|off")]
        remesh: slayer::pipeline::Remeshing,
    },
    /// List the GPU adapters wgpu can see, best first.
    Adapters {
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo { out, triangles } => demo::run(&out, triangles),
        Command::Scene {
            name,
            triangles,
            seed,
            jitter,
            output,
        } => scene::run(&name, triangles, seed, jitter, &output),
        Command::Check { file, json } => check::run(&file, json),
        Command::Adapters { json } => adapters(json),
        Command::Sculpt {
            input,
            strokes,
            output,
            stats,
            remesh,
        } => sculpt::run(&input, &strokes, &output, stats.as_deref(), remesh),
        Command::Remesh { file, edge, output } => remesh::run(&file, edge, &output),
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
        } => {
            let scenes = match bench::parse_scenes(&scene) {
                Ok(scenes) => scenes,
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::FAILURE;
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
            })
        }
    };
    match result {
        Ok(code) => code,
        Err(error) => {
            eprintln!("error: {}", one_line(&error));
            ExitCode::FAILURE
        }
    }
}

/// An error and its causes on one line.
fn one_line(error: &anyhow::Error) -> String {
    format!("{error:#}").replace('\n', " ")
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
