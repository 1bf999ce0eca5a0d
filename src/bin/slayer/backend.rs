//! `--backend cpu|gpu|auto|both`: which pipeline sculpts, chosen the same way by every command.

use slayer::gpu::{AdapterChoice, GpuContext, GpuKernels};
use slayer::pipeline::{CpuPipeline, PipelineSettings};

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
    pub pipeline: CpuPipeline,
    pub adapter: String,
    pub backend: Backend,
}

/// The CPU pipeline.
pub fn cpu(settings: PipelineSettings) -> Chosen {
    Chosen {
        pipeline: CpuPipeline::new(settings),
        adapter: "none (CPU)".into(),
        backend: Backend::Cpu,
    }
}

/// The GPU pipeline on any adapter (software ones too), or a clear error naming what to
/// install.
pub fn gpu(settings: PipelineSettings) -> anyhow::Result<Chosen> {
    let context = GpuContext::new(AdapterChoice {
        allow_software: true,
    })
    .map_err(|e| {
        anyhow::anyhow!(
            "--backend gpu: no GPU adapter ({e}); install a Vulkan driver (mesa-vulkan-drivers gives lavapipe) or use --backend cpu"
        )
    })?;
    Ok(on_gpu(context, settings))
}

fn on_gpu(context: GpuContext, settings: PipelineSettings) -> Chosen {
    Chosen {
        adapter: context.adapter.to_string(),
        pipeline: CpuPipeline::with_kernels(settings, Box::new(GpuKernels::new(context))),
        backend: Backend::Gpu,
    }
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
        Backend::Auto => match GpuContext::new(AdapterChoice {
            allow_software: false,
        }) {
            Ok(context) => {
                let chosen = on_gpu(context, settings);
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
