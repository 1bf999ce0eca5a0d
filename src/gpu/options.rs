//! [`GpuOptions`]: everything a user may choose about the GPU backend, in one value the
//! program passes in. The library reads no environment variables; `src/bin/` fills this from
//! its flags and from `WGPU_ADAPTER_NAME` and the `SLAYER_GPU_*` variables.

/// The resident-memory budget unless the user sets one: room for a 16M-face mesh (about
/// 1.8 GB resident with its room to grow, `resident_bytes`) with margin, well within an H100;
/// a desktop GPU with less memory should set its own.
pub const DEFAULT_GPU_BUDGET_MIB: u64 = 8192;

/// How the GPU backend is opened and what runs on it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GpuOptions {
    /// Accept a CPU rasterizer (lavapipe, llvmpipe) when no hardware GPU is present.
    pub allow_software: bool,
    /// Only adapters whose name contains this, ignoring case (`WGPU_ADAPTER_NAME`).
    pub adapter_name: Option<String>,
    /// Our own cap on what the backend keeps resident, in MiB: a larger mesh runs on the CPU
    /// (lavapipe never reports running out of memory).
    pub budget_mib: u64,
    /// Whether the proximity passes run on the GPU; `None`: on a hardware adapter only (on
    /// lavapipe their broad phase is hundreds of times slower than the CPU's face grid).
    pub proximity_on_gpu: Option<bool>,
    /// With the passes on the GPU, filter the exact backstop's first round there too.
    pub backstop_filter_on_gpu: bool,
    /// With the passes on the GPU, run a step's passes in the submission that selected and
    /// deformed it (else apart, once its moves are known).
    pub clamp_in_one_submission: bool,
    /// With those, record the samples given in one call in one submission behind the GPU's
    /// gate; `None`: on a hardware adapter only (on lavapipe the passes of a run, sized for
    /// the move they assume, cost several times what they cost apart).
    pub runs_ahead: Option<bool>,
}

impl Default for GpuOptions {
    fn default() -> GpuOptions {
        GpuOptions {
            allow_software: true,
            adapter_name: None,
            budget_mib: DEFAULT_GPU_BUDGET_MIB,
            proximity_on_gpu: None,
            backstop_filter_on_gpu: true,
            clamp_in_one_submission: true,
            runs_ahead: None,
        }
    }
}
