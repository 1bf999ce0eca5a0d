//! The `slayer` command line: generate scenes, check mesh files, run the demo.

mod check;
mod demo;
mod progress;
mod scene;

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
            output,
        } => scene::run(&name, triangles, seed, &output),
        Command::Check { file, json } => check::run(&file, json),
        Command::Adapters { json } => adapters(json),
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
