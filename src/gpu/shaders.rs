//! WGSL sources, embedded in the binary. A line `#import shared/NAME` is replaced by
//! `wgsl/shared/NAME.wgsl` (WGSL has no includes); sizes stay in WGSL `const`s, never pasted in.
//! A line `#paged NAME GROUP` declares an array split over the bindings of bind group GROUP,
//! read as `NAME(i)`: `wgsl/shared/paged_array.wgsl` with the name and group filled in (WGSL
//! has no generics either; see `super::pages`).

use thiserror::Error;

/// Shared snippets, by import name.
pub const SHARED: &[(&str, &str)] = &[
    ("shared/grid", include_str!("../../wgsl/shared/grid.wgsl")),
    ("shared/brdf", include_str!("../../wgsl/shared/brdf.wgsl")),
    ("shared/mesh", include_str!("../../wgsl/shared/mesh.wgsl")),
    ("shared/brush", include_str!("../../wgsl/shared/brush.wgsl")),
    ("shared/geom", include_str!("../../wgsl/shared/geom.wgsl")),
    ("shared/moves", include_str!("../../wgsl/shared/moves.wgsl")),
    ("shared/pages", include_str!("../../wgsl/shared/pages.wgsl")),
    ("shared/fixed", include_str!("../../wgsl/shared/fixed.wgsl")),
    ("shared/gate", include_str!("../../wgsl/shared/gate.wgsl")),
    (
        "shared/normals",
        include_str!("../../wgsl/shared/normals.wgsl"),
    ),
    (
        "shared/order_free",
        include_str!("../../wgsl/shared/order_free.wgsl"),
    ),
    (
        "shared/overlay",
        include_str!("../../wgsl/shared/overlay.wgsl"),
    ),
    (
        PAGED_ARRAY,
        include_str!("../../wgsl/shared/paged_array.wgsl"),
    ),
];

/// The template `#paged` lines expand; not imported directly.
const PAGED_ARRAY: &str = "shared/paged_array";

/// Compute kernels, by file stem; each has entry point `main`.
pub const KERNELS: &[(&str, &str)] = &[
    ("cell_keys", include_str!("../../wgsl/cell_keys.wgsl")),
    ("cell_counts", include_str!("../../wgsl/cell_counts.wgsl")),
    ("scan", include_str!("../../wgsl/scan.wgsl")),
    ("scan_add", include_str!("../../wgsl/scan_add.wgsl")),
    ("scatter", include_str!("../../wgsl/scatter.wgsl")),
    ("select", include_str!("../../wgsl/select.wgsl")),
    ("deform", include_str!("../../wgsl/deform.wgsl")),
    ("brush_frame", include_str!("../../wgsl/brush_frame.wgsl")),
    (
        "dispatch_args",
        include_str!("../../wgsl/dispatch_args.wgsl"),
    ),
    ("proximity", include_str!("../../wgsl/proximity.wgsl")),
    ("apply_moves", include_str!("../../wgsl/apply_moves.wgsl")),
    (
        "moving_entries",
        include_str!("../../wgsl/moving_entries.wgsl"),
    ),
    (
        "backstop_filter",
        include_str!("../../wgsl/backstop_filter.wgsl"),
    ),
    (
        "vertex_normals",
        include_str!("../../wgsl/vertex_normals.wgsl"),
    ),
    (
        "moved_normals",
        include_str!("../../wgsl/moved_normals.wgsl"),
    ),
    (
        "overlay_members",
        include_str!("../../wgsl/overlay_members.wgsl"),
    ),
    ("overlay_keys", include_str!("../../wgsl/overlay_keys.wgsl")),
    ("longest_move", include_str!("../../wgsl/longest_move.wgsl")),
    ("sample_gate", include_str!("../../wgsl/sample_gate.wgsl")),
    ("moved_edges", include_str!("../../wgsl/moved_edges.wgsl")),
    (
        "overlay_entries",
        include_str!("../../wgsl/overlay_entries.wgsl"),
    ),
];

/// Render shaders in `wgsl/render/`, by file stem; each has entry points `vs_main` (vertex)
/// and `fs_main` (fragment).
pub const RENDER_SHADERS: &[(&str, &str)] =
    &[("preview", include_str!("../../wgsl/render/preview.wgsl"))];

/// Entry points every render shader has.
pub const VERTEX_ENTRY: &str = "vs_main";
pub const FRAGMENT_ENTRY: &str = "fs_main";
/// The preview shader's second vertex stage: positions and normals from the GPU backend's own
/// buffers (`wgsl/render/preview.wgsl`).
pub const ENGINE_VERTEX_ENTRY: &str = "vs_engine";

#[derive(Debug, Error)]
pub enum ShaderError {
    #[error("no kernel named `{0}`")]
    UnknownKernel(String),
    #[error("no render shader named `{0}`")]
    UnknownRenderShader(String),
    #[error("{file}: unknown import `{import}`")]
    UnknownImport { file: String, import: String },
    #[error("{file}: `{line}` should read `#paged NAME GROUP` (a WGSL name, a bind group above 0)")]
    BadPaged { file: String, line: String },
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

/// Replaces `#import` lines by the shared snippet they name (one level; snippets import
/// nothing), and `#paged` lines by the paged-array template filled in.
pub fn expand_imports(file: &str, text: &str) -> Result<String, ShaderError> {
    let mut out = String::with_capacity(text.len() + 1024);
    for line in text.lines() {
        let directive = line.split_whitespace().next();
        if directive == Some("#paged") {
            let declaration = line.trim().trim_start_matches("#paged");
            out.push_str(&paged_array(file, declaration)?);
        } else if let Some(import) = line.trim().strip_prefix("#import ") {
            let import = import.trim();
            if import == PAGED_ARRAY {
                return Err(ShaderError::UnknownImport {
                    file: file.to_string(),
                    import: format!("{import} (declare paged arrays with `#paged NAME GROUP`)"),
                });
            }
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

/// The template of `#paged NAME GROUP`, filled in.
fn paged_array(file: &str, declaration: &str) -> Result<String, ShaderError> {
    let bad = || ShaderError::BadPaged {
        file: file.to_string(),
        line: format!("#paged {declaration}"),
    };
    let mut words = declaration.split_whitespace();
    let (Some(name), Some(group), None) = (words.next(), words.next(), words.next()) else {
        return Err(bad());
    };
    let named = name.starts_with(|c: char| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !named || group.parse::<u32>().map_or(true, |g| g == 0) {
        return Err(bad());
    }
    let (_, template) = SHARED
        .iter()
        .find(|(n, _)| *n == PAGED_ARRAY)
        .expect("the template is registered");
    // The template's opening comment speaks of the placeholders themselves: left out.
    let body: Vec<&str> = template
        .lines()
        .skip_while(|line| line.starts_with("//"))
        .collect();
    Ok(body
        .join("\n")
        .replace("PAGE_GROUP", group)
        .replace("PAGED", name))
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
