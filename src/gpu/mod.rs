//! The GPU path: adapter choice, shader loading and the compute kernels' host side (DESIGN §6).
//! Each kernel in `wgsl/` has a CPU mirror of the same name in [`crate::cpu`].

mod cell_keys;
mod context;
mod layout;
pub mod shaders;

pub use cell_keys::run_cell_keys;
pub use context::{AdapterChoice, AdapterSummary, GpuContext, GpuError, list_adapters};
pub use layout::CellKeyParams;
