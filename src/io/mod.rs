//! Mesh files: OBJ (tobj underneath, one layer per `o`/`g`, materials from its `.mtl`) and PLY
//! (per-vertex BRDF or colours, layer ids). Readers never panic on malformed input: every
//! problem becomes an [`IoError`] naming the file and, where it applies, the line; a readable
//! file that is not a clean manifold mesh is repaired and the repairs reported
//! ([`ImportReport`]), or refused when the options say strict. Only regular files are read, at most
//! [`MAX_INPUT_BYTES`](crate::files::MAX_INPUT_BYTES) of them. Writers go through temporary files
//! and renames ([`AtomicBatch`]), so a failed write never leaves half a mesh where a good one
//! was, nor an OBJ without its `.mtl`.

mod atomic;
mod error;
mod gltf;
mod gltf_write;
mod import;
mod mtl;
mod obj;
mod ply;
mod stl;
mod weld;

pub use atomic::{AtomicBatch, sweep_stale_temporaries, write_atomically};
pub use error::IoError;
pub use gltf_write::{write_glb, write_gltf};
pub use import::{ImportOptions, ImportReport};
pub use mtl::{layer_materials, material_brdf, write_mtl};
pub use obj::{LibraryReader, write_obj, write_obj_with_materials};
pub use ply::{write_ply, write_ply_with};
pub use stl::write_stl;

use std::io::Write;
use std::path::{Component, Path};

use crate::mesh::{LayerId, Mesh};
use import::Parsed;

/// File formats by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Obj,
    Ply,
    Stl,
    /// Binary glTF 2.0.
    Glb,
    /// glTF 2.0 as JSON.
    Gltf,
}

impl Format {
    pub fn of_path(path: &Path) -> Result<Format, IoError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("obj") => Ok(Format::Obj),
            Some("ply") => Ok(Format::Ply),
            Some("stl") => Ok(Format::Stl),
            Some("glb") => Ok(Format::Glb),
            Some("gltf") => Ok(Format::Gltf),
            _ => Err(IoError::UnsupportedFormat {
                path: path.display().to_string(),
            }),
        }
    }
}

/// Which way is up in a file: slayer works Z-up; many modelling tools write Y-up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UpAxis {
    Y,
    Z,
}

impl UpAxis {
    /// What a file's format suggests: Z for slayer's own files, sessions, glTF (turned to Z-up
    /// on import) and STL (3-D printing is Z-up); Y for other tools' OBJ and PLY (Blender,
    /// ZBrush and Maya write OBJ Y-up, and so are the common PLY scans).
    pub fn guess(path: &Path) -> UpAxis {
        let Ok(format) = Format::of_path(path) else {
            return UpAxis::Z;
        };
        if !matches!(format, Format::Obj | Format::Ply) {
            return UpAxis::Z;
        }
        let mut head = [0u8; 4096];
        let read = std::fs::File::open(path)
            .and_then(|mut f| std::io::Read::read(&mut f, &mut head))
            .unwrap_or(0);
        let head = &head[..read];
        let ours = head.starts_with(b"# slayer mesh")
            || head
                .windows(26)
                .any(|w| w == b"comment written by slayer\n");
        if ours { UpAxis::Z } else { UpAxis::Y }
    }

    /// Turns `mesh` so that this axis points along +Z (a quarter turn about X for Y-up, exact
    /// in floats), with its normals.
    pub fn to_z_up(self, mesh: &mut Mesh) {
        if self == UpAxis::Y {
            for p in mesh.positions_mut() {
                *p = gltf::from_y_up(*p);
            }
            mesh.recompute_normals();
        }
    }
}

/// Reads a mesh, repaired where it needs it: malformed files, non-finite values and what no
/// repair can mend are errors.
pub fn read_mesh(path: &Path) -> Result<Mesh, IoError> {
    import_mesh(path, &ImportOptions::default()).map(|(mesh, _)| mesh)
}

/// [`read_mesh`] with `options`, and the report of what the import repaired and left out.
pub fn import_mesh(path: &Path, options: &ImportOptions) -> Result<(Mesh, ImportReport), IoError> {
    let (mesh, report) = load_mesh(path, options)?;
    refuse_unusable(mesh, report, &path.display().to_string())
}

/// [`read_mesh`] on bytes already in memory (`name` is used in messages; an OBJ's material
/// libraries are not read).
pub fn read_mesh_bytes(bytes: &[u8], format: Format, name: &str) -> Result<Mesh, IoError> {
    import_bytes(bytes, format, name, &ImportOptions::default()).map(|(mesh, _)| mesh)
}

/// [`import_mesh`] on bytes already in memory.
pub fn import_bytes(
    bytes: &[u8],
    format: Format,
    name: &str,
    options: &ImportOptions,
) -> Result<(Mesh, ImportReport), IoError> {
    let (mesh, report) = load_mesh_bytes(bytes, format, name, options, &no_libraries)?;
    refuse_unusable(mesh, report, name)
}

/// Refuses non-finite positions (which `check` reports instead) and anything the mesh's own
/// validation finds.
fn refuse_unusable(
    mesh: Mesh,
    report: ImportReport,
    name: &str,
) -> Result<(Mesh, ImportReport), IoError> {
    if report.non_finite_vertices > 0 {
        return Err(IoError::Parse {
            path: name.to_string(),
            line: report.first_non_finite_line,
            message: format!(
                "{} vertices have a non-finite coordinate (NaN or infinity)",
                report.non_finite_vertices
            ),
        });
    }
    mesh.validate()
        .map_err(|source| IoError::mesh(name.to_string(), source, &mesh))?;
    Ok((mesh, report))
}

/// Reads a mesh that is well-formed as a file and, repaired unless strict, as a manifold
/// surface, but lets non-finite or out-of-range values through (counted in the report) so that
/// `slayer check` can report them.
pub fn load_mesh(path: &Path, options: &ImportOptions) -> Result<(Mesh, ImportReport), IoError> {
    let format = Format::of_path(path)?;
    let folder = path.parent().unwrap_or(Path::new("."));
    let beside = |library: &str| read_library(folder, library);
    let name = path.display().to_string();
    // The file's bytes go before the mesh is built: they would be a third of the peak.
    let parsed = parse(&read_bytes(path)?, format, &name, &beside)?;
    import::build(parsed, options, &name)
}

/// [`load_mesh`] on bytes already in memory; `libraries` reads the material libraries an OBJ
/// names.
pub fn load_mesh_bytes(
    bytes: &[u8],
    format: Format,
    name: &str,
    options: &ImportOptions,
    libraries: LibraryReader<'_>,
) -> Result<(Mesh, ImportReport), IoError> {
    import::build(parse(bytes, format, name, libraries)?, options, name)
}

fn parse(
    bytes: &[u8],
    format: Format,
    name: &str,
    libraries: LibraryReader<'_>,
) -> Result<Parsed, IoError> {
    match format {
        Format::Obj => obj::parse_obj(bytes, name, libraries),
        Format::Ply => ply::parse_ply(bytes, name),
        Format::Stl => stl::parse_stl(bytes, name),
        Format::Glb | Format::Gltf => gltf::parse_gltf(bytes, name, libraries),
    }
}

/// A reader of material libraries for bytes that came from no folder.
pub fn no_libraries(_: &str) -> Result<Vec<u8>, String> {
    Err("the mesh was not read from a folder".into())
}

/// Bytes a writer gathers before handing them on.
const WRITE_CHUNK: usize = 1 << 16;

/// Hands `buffer` on to `out` once it holds a chunk.
fn flush_chunk(out: &mut impl Write, buffer: &mut Vec<u8>) -> std::io::Result<()> {
    if buffer.len() >= WRITE_CHUNK {
        out.write_all(buffer)?;
        buffer.clear();
    }
    Ok(())
}

/// A file another names in `folder` (an OBJ's material library, a `.gltf`'s buffer): a relative
/// path that stays in the folder (a file must not make slayer read `/etc/passwd` or
/// `../../secret`).
fn read_library(folder: &Path, library: &str) -> Result<Vec<u8>, String> {
    let relative = Path::new(library);
    if !relative
        .components()
        .all(|c| matches!(c, Component::Normal(_) | Component::CurDir))
    {
        return Err("only a file in the OBJ's folder is read".into());
    }
    crate::files::read_input(&folder.join(relative), crate::files::MAX_INPUT_BYTES)
        .map_err(|e| e.to_string())
}

fn read_bytes(path: &Path) -> Result<Vec<u8>, IoError> {
    crate::files::read_input(path, crate::files::MAX_INPUT_BYTES).map_err(|source| IoError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// The bytes of a mesh in `format`.
pub fn encode_mesh(mesh: &Mesh, format: Format) -> Vec<u8> {
    let mut bytes = Vec::new();
    // Writing into a Vec cannot fail.
    let _ = match format {
        Format::Obj => write_obj(mesh, &mut bytes),
        Format::Ply => write_ply(mesh, &mut bytes),
        Format::Stl => write_stl(mesh, &mut bytes),
        Format::Glb => write_glb(mesh, &mut bytes),
        Format::Gltf => write_gltf(mesh, &mut bytes),
    };
    bytes
}

/// Writes a mesh in the format its extension names, atomically. An OBJ gets a material library
/// beside it (`NAME.mtl`, one material per layer) that it names with `mtllib`; the two are
/// written as one ([`AtomicBatch`]).
pub fn write_mesh(mesh: &Mesh, path: &Path) -> Result<(), IoError> {
    let mut batch = AtomicBatch::new();
    stage_mesh(&mut batch, mesh, path)?;
    batch.commit()
}

/// Stages a mesh's file (and an OBJ's `.mtl`) in `batch`, to be written with other files as
/// one unit. The file is streamed: a mesh is never held twice in memory, once as bytes.
pub fn stage_mesh(batch: &mut AtomicBatch, mesh: &Mesh, path: &Path) -> Result<(), IoError> {
    stage_mesh_with(batch, mesh, path, &[])
}

/// [`stage_mesh`] with the layers whose proximity policy is fuse: a PLY keeps them in its
/// header; the other formats have no place for them.
pub fn stage_mesh_with(
    batch: &mut AtomicBatch,
    mesh: &Mesh,
    path: &Path,
    fuse_layers: &[LayerId],
) -> Result<(), IoError> {
    match Format::of_path(path)? {
        Format::Ply => {
            batch.stage_with(path, |mut out| write_ply_with(mesh, fuse_layers, &mut out))
        }
        Format::Stl => batch.stage_with(path, |mut out| write_stl(mesh, &mut out)),
        Format::Glb => batch.stage_with(path, |mut out| write_glb(mesh, &mut out)),
        Format::Gltf => batch.stage_with(path, |mut out| write_gltf(mesh, &mut out)),
        Format::Obj => {
            let library = path.with_extension("mtl");
            let library_name = library
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "materials.mtl".into());
            batch.stage_with(path, |mut out| {
                write_obj_with_materials(mesh, &mut out, Some(&library_name))
            })?;
            batch.stage_with(&library, |mut out| write_mtl(mesh, &mut out))
        }
    }
}
