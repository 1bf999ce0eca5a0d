use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use slayer::bench::{ScriptSpec, generate_script, gpu_memory_lines, paper_table};
use slayer::brush::{BrushKind, PaintSpec, StencilSpec, Stroke, StrokeFile};
use slayer::gpu::GpuContext;
use slayer::mesh::Mesh;
use slayer::pipeline::PipelineSettings;
use slayer::render::{Image, RenderOptions};
use slayer::scene::{SceneKind, SceneSpec, generate};

use crate::progress::Steps;

/// Strokes in the demo's script: enough to see every brush of the bench mix at work.
const DEMO_STROKES: usize = 12;
/// Size of each of the before and after images.
const IMAGE_SIZE: (u32, u32) = (1280, 960);

/// The demo paints as it sculpts (sLayer paints and deforms in one pass): pushed-in strokes
/// leave rust where they press, the others leave red paint, and every third stroke lays a
/// stencil of bare-metal spots in rust.
fn add_paint(script: &mut StrokeFile) {
    for (i, stroke) in script.strokes.iter_mut().enumerate() {
        stroke.paint = match stroke.brush {
            _ if i % 3 == 2 => Some(PaintSpec {
                stencil: Some(StencilSpec {
                    pattern: Some("spots".into()),
                    png: None,
                    with: Some("bare-metal".into()),
                    tile: 0.6 * stroke.radius,
                }),
                ..PaintSpec::material("rust")
            }),
            BrushKind::Draw if stroke.invert => Some(PaintSpec::material("rust")),
            BrushKind::Smooth => None,
            _ => Some(PaintSpec {
                opacity: Some(0.8),
                ..PaintSpec::material("red-paint")
            }),
        };
    }
}

/// Renders the mesh to `path`; returns the image.
fn render_to(gpu: &GpuContext, mesh: &Mesh, path: &Path) -> anyhow::Result<Image> {
    let options = RenderOptions {
        width: IMAGE_SIZE.0,
        height: IMAGE_SIZE.1,
        ..RenderOptions::default()
    };
    let started = Instant::now();
    let rendered = crate::render::render_png(gpu, mesh, &options, path)?;
    println!(
        "  rendered {} faces at {}×{} in {:.0} ms -> {}",
        rendered.faces,
        options.width,
        options.height,
        started.elapsed().as_secs_f64() * 1e3,
        path.display()
    );
    Ok(rendered.image)
}

/// Generates the default material (peeling plaster), sculpts it with a short seeded stroke
/// script, writes the material before and after, checks the result and prints the timings.
pub fn run(
    out: &Path,
    triangles: usize,
    backend: crate::backend::Backend,
) -> anyhow::Result<ExitCode> {
    // The backend first: a wrong choice fails before minutes of work.
    let mut pipeline = crate::backend::choose(backend, PipelineSettings::default())?.pipeline;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let (mut mesh, strokes, strokes_path) = generate_scene_and_strokes(out, triangles)?;

    // Rendering needs some Vulkan adapter (lavapipe will do); without one the demo still
    // sculpts and says what to install.
    let gpu = match crate::render::open_gpu() {
        Ok(gpu) => Some(gpu),
        Err(e) => {
            eprintln!("warning: no images: {}", crate::one_line(&e));
            None
        }
    };
    let before_image = match &gpu {
        Some(gpu) => Some(render_to(gpu, &mesh, &out.join("plaster-before.png"))?),
        None => None,
    };

    println!(
        "  sculpting {} strokes ({}) on the {} backend -> {}",
        strokes.len(),
        strokes
            .iter()
            .map(|s| s.brush.kind.name())
            .collect::<Vec<_>>()
            .join(", "),
        pipeline.name(),
        strokes_path.display()
    );
    let result = crate::bench::sculpt_with_progress(
        "plaster",
        &mut mesh,
        &strokes,
        &mut pipeline,
        Default::default(),
    )?;
    if let Some(why) = pipeline.kernel_failure() {
        eprintln!("warning: the GPU failed ({why}); the strokes finished on the CPU");
    }
    println!("{}", paper_table(std::slice::from_ref(&result)));
    print!("{}", gpu_memory_lines(std::slice::from_ref(&result)));

    let after = write_sculpted(out, &mesh)?;
    if let (Some(gpu), Some(before_image)) = (&gpu, before_image) {
        let after_image = render_to(gpu, &mesh, &out.join("plaster-after.png"))?;
        let both = out.join("plaster-before-after.png");
        let side_by_side = before_image.beside(&after_image, 16, [255, 255, 255, 255]);
        slayer::io::write_atomically(&both, &side_by_side.to_png()?)?;
        println!("  before and after side by side -> {}", both.display());
    }
    let report = crate::check::report(&after, None, true)?;
    println!("{report}");
    Ok(if report.is_clean() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// The default material at `triangles`, written to `plaster.ply`, and the demo's painted
/// strokes over it, written to `strokes.json` (returned with its path).
fn generate_scene_and_strokes(
    out: &Path,
    triangles: usize,
) -> anyhow::Result<(Mesh, Vec<Stroke>, PathBuf)> {
    let spec = SceneSpec {
        triangles,
        ..SceneSpec::new(SceneKind::Plaster)
    };
    println!(
        "slayer demo: default material `{}` with {} triangles",
        spec.kind, spec.triangles
    );
    let started = Instant::now();
    let steps = Steps::new("demo");
    steps.step("generating");
    let mesh = generate(&spec)?;
    let before = out.join("plaster.ply");
    steps.step(&format!("writing {}", before.display()));
    slayer::io::write_mesh(&mesh, &before)?;
    let mut script = generate_script(
        &mesh,
        &ScriptSpec {
            strokes: DEMO_STROKES,
            ..ScriptSpec::default()
        },
    );
    add_paint(&mut script);
    let strokes_path = out.join("strokes.json");
    slayer::io::write_atomically(&strokes_path, script.to_json().as_bytes())?;
    let strokes = script.resolve(&mesh, &strokes_path.display().to_string())?;
    steps.finish();
    println!(
        "  generated {} layers, {} vertices, {} faces in {:.1} s -> {}",
        mesh.layer_count(),
        mesh.live_vertex_count(),
        mesh.live_face_count(),
        started.elapsed().as_secs_f64(),
        before.display()
    );
    Ok((mesh, strokes, strokes_path))
}

/// Writes the sculpted mesh as PLY and as OBJ with its `.mtl`; returns the PLY's path.
fn write_sculpted(out: &Path, mesh: &Mesh) -> anyhow::Result<PathBuf> {
    let after = out.join("plaster-sculpted.ply");
    let after_obj = out.join("plaster-sculpted.obj");
    slayer::io::write_mesh(mesh, &after)?;
    slayer::io::write_mesh(mesh, &after_obj)?;
    println!(
        "  wrote {}, {} and {}",
        after.display(),
        after_obj.display(),
        after_obj.with_extension("mtl").display()
    );
    Ok(after)
}
