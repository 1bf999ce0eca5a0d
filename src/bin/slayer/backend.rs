//! `--backend cpu|gpu|auto|both`: which pipeline sculpts, chosen the same way by every command.

use slayer::gpu::{GpuContext, GpuKernels, GpuOptions};
use slayer::pipeline::{Pipeline, PipelineSettings};

/// The GPU options the environment sets: `WGPU_ADAPTER_NAME` (wgpu's convention) pins an
/// adapter by name; `SLAYER_GPU_BUDGET_MIB` caps what the backend keeps resident;
/// `SLAYER_GPU_PROXIMITY`, `SLAYER_GPU_BACKSTOP`, `SLAYER_GPU_AHEAD` and
/// `SLAYER_GPU_RUN_AHEAD` (`1` on, `0` off) choose what runs on the GPU. The only place the
/// program reads them.
pub fn gpu_options(allow_software: bool) -> GpuOptions {
    let var = |name: &str| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
    let switch = |name: &str| var(name).map(|v| v.trim() == "1");
    let defaults = GpuOptions::default();
    GpuOptions {
        allow_software,
        adapter_name: var("WGPU_ADAPTER_NAME"),
        budget_mib: var("SLAYER_GPU_BUDGET_MIB")
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or(defaults.budget_mib),
        proximity_on_gpu: switch("SLAYER_GPU_PROXIMITY"),
        backstop_filter_on_gpu: switch("SLAYER_GPU_BACKSTOP")
            .unwrap_or(defaults.backstop_filter_on_gpu),
        clamp_in_one_submission: switch("SLAYER_GPU_AHEAD")
            .unwrap_or(defaults.clamp_in_one_submission),
        runs_ahead: switch("SLAYER_GPU_RUN_AHEAD"),
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    Cpu,
    /// The GPU's selection, deformation and proximity passes (the exact backstop and remeshing
    /// on the CPU); any adapter, lavapipe included — asking for it by name is asking for it.
    Gpu,
    /// A hardware GPU if there is one, else the CPU.
    Auto,
    /// The CPU and the GPU on the same strokes, compared (`bench` only).
    Both,
}

impl std::str::FromStr for Backend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "cpu" => Ok(Backend::Cpu),
            "gpu" => Ok(Backend::Gpu),
            "auto" => Ok(Backend::Auto),
            "both" => Ok(Backend::Both),
            other => Err(format!(
                "unknown backend `{other}` (expected cpu, gpu, auto or both)"
            )),
        }
    }
}

/// A pipeline, the adapter it runs on ("none (CPU)" for the CPU), and which backend that is
/// (`Cpu` or `Gpu`: what `auto` resolved to).
pub struct Chosen {
    pub pipeline: Pipeline,
    pub adapter: String,
    pub backend: Backend,
}

/// The CPU pipeline.
pub fn cpu(settings: PipelineSettings) -> Chosen {
    Chosen {
        pipeline: Pipeline::new(settings),
        adapter: "none (CPU)".into(),
        backend: Backend::Cpu,
    }
}

/// The GPU pipeline on any adapter (software ones too), or a clear error naming what to
/// install.
pub fn gpu(settings: PipelineSettings) -> anyhow::Result<Chosen> {
    let options = gpu_options(true);
    let context = GpuContext::open(&options).map_err(|e| {
        anyhow::anyhow!(
            "--backend gpu: no GPU adapter ({e}); install a Vulkan driver (mesa-vulkan-drivers gives lavapipe) or use --backend cpu"
        )
    })?;
    Ok(on_gpu(context, &options, settings))
}

fn on_gpu(context: GpuContext, options: &GpuOptions, settings: PipelineSettings) -> Chosen {
    let kernels = GpuKernels::with_options(context, options);
    Chosen {
        adapter: kernels.adapter().to_string(),
        pipeline: Pipeline::with_kernels(settings, Box::new(kernels)),
        backend: Backend::Gpu,
    }
}

/// As [`choose`], with the GPU backend's device for a window to share (the app's).
pub fn choose_sharing(
    backend: Backend,
    settings: PipelineSettings,
) -> anyhow::Result<(Chosen, Option<slayer::app::SharedDevice>)> {
    let (context, options) = match backend {
        Backend::Gpu => {
            let options = gpu_options(true);
            match GpuContext::open(&options) {
                Ok(context) => (context, options),
                // `gpu` says why it cannot.
                Err(_) => return gpu(settings).map(|chosen| (chosen, None)),
            }
        }
        Backend::Auto => match GpuContext::open(&gpu_options(false)) {
            Ok(context) => (context, gpu_options(false)),
            Err(_) => return choose(backend, settings).map(|chosen| (chosen, None)),
        },
        _ => return choose(backend, settings).map(|chosen| (chosen, None)),
    };
    let shared = slayer::app::SharedDevice::of(&context);
    Ok((on_gpu(context, &options, settings), Some(shared)))
}

/// `cpu`, `gpu` or `auto`, saying what `auto` chose; `both` runs two pipelines, which only
/// `slayer bench` does.
pub fn choose(backend: Backend, settings: PipelineSettings) -> anyhow::Result<Chosen> {
    match backend {
        Backend::Cpu => Ok(cpu(settings)),
        Backend::Gpu => gpu(settings),
        Backend::Both => anyhow::bail!(
            "--backend both compares the two paths in `slayer bench`; here use cpu, gpu or auto"
        ),
        Backend::Auto => match GpuContext::open(&gpu_options(false)) {
            Ok(context) => {
                let chosen = on_gpu(context, &gpu_options(false), settings);
                println!("backend auto: the GPU, on {}", chosen.adapter);
                Ok(chosen)
            }
            Err(_) => {
                println!("backend auto: the CPU (no hardware GPU; --backend gpu runs on lavapipe)");
                Ok(cpu(settings))
            }
        },
    }
}
