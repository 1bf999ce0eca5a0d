//! WGSL sources, embedded in the binary. A line `#import shared/NAME` is replaced by
//! `wgsl/shared/NAME.wgsl` (WGSL has no includes); sizes stay in WGSL `const`s, never pasted in.

use thiserror::Error;

/// Shared snippets, by import name.
pub const SHARED: &[(&str, &str)] = &[
    ("shared/grid", include_str!("../../wgsl/shared/grid.wgsl")),
    ("shared/brdf", include_str!("../../wgsl/shared/brdf.wgsl")),
    ("shared/mesh", include_str!("../../wgsl/shared/mesh.wgsl")),
    ("shared/brush", include_str!("../../wgsl/shared/brush.wgsl")),
    ("shared/geom", include_str!("../../wgsl/shared/geom.wgsl")),
    ("shared/moves", include_str!("../../wgsl/shared/moves.wgsl")),
];

/// Compute kernels, by file stem; each has entry point `main`.
pub const KERNELS: &[(&str, &str)] = &[
    ("cell_keys", include_str!("../../wgsl/cell_keys.wgsl")),
    ("cell_counts", include_str!("../../wgsl/cell_counts.wgsl")),
    ("scan", include_str!("../../wgsl/scan.wgsl")),
    ("scan_add", include_str!("../../wgsl/scan_add.wgsl")),
    ("scatter", include_str!("../../wgsl/scatter.wgsl")),
    ("select", include_str!("../../wgsl/select.wgsl")),
    ("deform", include_str!("../../wgsl/deform.wgsl")),
    (
        "dispatch_args",
        include_str!("../../wgsl/dispatch_args.wgsl"),
    ),
    ("proximity", include_str!("../../wgsl/proximity.wgsl")),
    ("apply_moves", include_str!("../../wgsl/apply_moves.wgsl")),
    (
        "vertex_normals",
        include_str!("../../wgsl/vertex_normals.wgsl"),
    ),
];

/// Render shaders in `wgsl/render/`, by file stem; each has entry points `vs_main` (vertex)
/// and `fs_main` (fragment).
pub const RENDER_SHADERS: &[(&str, &str)] =
    &[("preview", include_str!("../../wgsl/render/preview.wgsl"))];

/// Entry points every render shader has.
pub const VERTEX_ENTRY: &str = "vs_main";
pub const FRAGMENT_ENTRY: &str = "fs_main";

#[derive(Debug, Error)]
pub enum ShaderError {
    #[error("no kernel named `{0}`")]
    UnknownKernel(String),
    #[error("no render shader named `{0}`")]
    UnknownRenderShader(String),
    #[error("{file}: unknown import `{import}`")]
    UnknownImport { file: String, import: String },
    #[error("{file}: WGSL does not validate:\n{message}")]
    Invalid { file: String, message: String },
}

/// The kernel's source with its imports expanded.
pub fn kernel_source(name: &str) -> Result<String, ShaderError> {
    let (_, text) = KERNELS
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| ShaderError::UnknownKernel(name.to_string()))?;
    expand_imports(name, text)
}

/// The render shader's source with its imports expanded.
pub fn render_source(name: &str) -> Result<String, ShaderError> {
    let (_, text) = RENDER_SHADERS
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| ShaderError::UnknownRenderShader(name.to_string()))?;
    expand_imports(&format!("render/{name}"), text)
}

/// Replaces `#import` lines by the shared snippet they name (one level; snippets import nothing).
pub fn expand_imports(file: &str, text: &str) -> Result<String, ShaderError> {
    let mut out = String::with_capacity(text.len() + 1024);
    for line in text.lines() {
        if let Some(import) = line.trim().strip_prefix("#import ") {
            let import = import.trim();
            let (_, snippet) = SHARED.iter().find(|(n, _)| *n == import).ok_or_else(|| {
                ShaderError::UnknownImport {
                    file: file.to_string(),
                    import: import.to_string(),
                }
            })?;
            out.push_str(snippet);
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    Ok(out)
}

/// Parses and validates WGSL with naga, reporting every error with its source location.
pub fn validate(
    file: &str,
    source: &str,
) -> Result<(naga::Module, naga::valid::ModuleInfo), ShaderError> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| ShaderError::Invalid {
        file: file.to_string(),
        message: e.emit_to_string(source),
    })?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| ShaderError::Invalid {
        file: file.to_string(),
        message: e.emit_to_string(source),
    })?;
    Ok((module, info))
}
