//! Reflectance and the preview renderer (docs/design.md, "Materials and rendering", sLayer's "Reflectance Editing").
//!
//! [`brdf`] is the microfacet model over the linear BRDF parametrization, on the CPU: the
//! reference the WGSL preview shader mirrors and the tests check. [`preview`] renders a mesh
//! offscreen through wgpu (lavapipe included) into an [`Image`] that is written as PNG.

pub mod brdf;
mod camera;
mod image;
mod preview;

pub use camera::{Camera, CameraSpec, FIELD_OF_VIEW_DEGREES};
pub use image::{Image, ImageDifference, ImageError};
pub use preview::{
    BACKGROUND, MAX_PIXELS, PALETTE, PreviewUniforms, RenderError, RenderOptions, RenderVertex,
    Rendered, render,
};
pub(crate) use preview::{
    MSAA_SAMPLES, Targets as PreviewTargets, VertexPull, bind_group as preview_bind_group,
    pipeline as preview_pipeline, record_draws as record_preview_draws, render_vertex,
    uniforms as preview_uniforms,
};
