//! `slayer render`: a mesh file to a PNG through the preview renderer, headless.

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, bail};
use slayer::gpu::GpuContext;
use slayer::io::UpAxis;
use slayer::mesh::{LayerId, Mesh};
use slayer::render::{CameraSpec, RenderOptions, Rendered, render};

/// `W×H`, `WxH` or `WXH`.
pub fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let parts: Vec<&str> = text.split(['x', 'X', '×']).map(str::trim).collect();
    let [w, h] = parts[..] else {
        return Err(format!("`{text}` is not WIDTHxHEIGHT (e.g. 1920x1080)"));
    };
    let side = |s: &str| {
        s.parse::<u32>()
            .map_err(|_| format!("`{s}` in size `{text}` is not a whole number of pixels"))
    };
    let (width, height) = (side(w)?, side(h)?);
    if width == 0 || height == 0 {
        return Err(format!("size `{text}` has no pixels"));
    }
    Ok((width, height))
}

pub fn parse_camera(text: &str) -> Result<CameraSpec, String> {
    text.parse()
}

/// Layer choices by index or name, checked against the mesh.
pub fn resolve_layers(mesh: &Mesh, names: &[String]) -> anyhow::Result<Vec<LayerId>> {
    names
        .iter()
        .map(|name| {
            let found = match name.parse::<u32>() {
                Ok(i) => ((i as usize) < mesh.layer_count()).then_some(i),
                Err(_) => mesh
                    .layer_names()
                    .iter()
                    .position(|n| n == name)
                    .map(|i| i as LayerId),
            };
            found.with_context(|| {
                format!(
                    "--layers: no layer `{name}` (the mesh has {}: {})",
                    mesh.layer_count(),
                    mesh.layer_names().join(", ")
                )
            })
        })
        .collect()
}

/// The GPU the preview renders on: any adapter, software ones included, since headless
/// machines render on lavapipe.
pub fn open_gpu() -> anyhow::Result<GpuContext> {
    GpuContext::open(&crate::backend::gpu_options(true)).context(
        "rendering needs a Vulkan adapter; without a GPU install Mesa's lavapipe \
         (`apt-get install mesa-vulkan-drivers`, or run tools/test.sh)",
    )
}

/// Renders and writes a PNG; returns what was rendered.
pub fn render_png(
    gpu: &GpuContext,
    mesh: &Mesh,
    options: &RenderOptions,
    output: &Path,
) -> anyhow::Result<Rendered> {
    let rendered = render(gpu, mesh, options)?;
    let png = rendered.image.to_png()?;
    slayer::io::write_atomically(output, &png)?;
    Ok(rendered)
}

pub struct Args<'a> {
    pub file: &'a Path,
    pub output: &'a Path,
    pub size: (u32, u32),
    pub camera: CameraSpec,
    pub layers: &'a [String],
    pub false_colour: bool,
    pub wireframe: bool,
    pub antialias: bool,
    /// `auto`, `y` or `z`: which axis of the file points up.
    pub up: &'a str,
    /// Refuse a mesh file that needs repairs.
    pub strict: bool,
}

pub fn run(args: &Args<'_>) -> anyhow::Result<ExitCode> {
    if !args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        bail!("{}: the output must be a .png file", args.output.display());
    }
    let started = Instant::now();
    let mut mesh = crate::open::open(args.file, args.strict)?.into_mesh();
    let up = match args.up {
        "y" => UpAxis::Y,
        "z" => UpAxis::Z,
        _ => UpAxis::guess(args.file),
    };
    up.to_z_up(&mut mesh);
    let load_ms = started.elapsed().as_secs_f64() * 1e3;
    let layers = if args.layers.is_empty() {
        None
    } else {
        Some(resolve_layers(&mesh, args.layers)?)
    };
    let started = Instant::now();
    let gpu = open_gpu()?;
    let gpu_ms = started.elapsed().as_secs_f64() * 1e3;
    let options = RenderOptions {
        width: args.size.0,
        height: args.size.1,
        camera: args.camera,
        layers,
        false_colour: args.false_colour,
        wireframe: args.wireframe,
        antialias: args.antialias,
        max_vertices_per_draw: None,
    };
    let started = Instant::now();
    let rendered = render_png(&gpu, &mesh, &options, args.output)?;
    let render_ms = started.elapsed().as_secs_f64() * 1e3;
    if rendered.faces == 0 {
        eprintln!(
            "warning: {}: nothing to draw (no faces on the chosen layers); the image is background only",
            args.file.display()
        );
    }
    println!(
        "rendered {} faces in {} draw{} at {}×{}, {:?} up, on {}: {render_ms:.0} ms \
         including the PNG (reading the mesh {load_ms:.0} ms, opening the adapter {gpu_ms:.0} ms) -> {}",
        rendered.faces,
        rendered.draws,
        if rendered.draws == 1 { "" } else { "s" },
        options.width,
        options.height,
        up,
        gpu.adapter,
        args.output.display()
    );
    Ok(ExitCode::SUCCESS)
}
