//! Mesh files: OBJ (tobj underneath, one layer per `o`/`g`) and PLY (per-vertex BRDF and layer
//! ids). Readers never panic on malformed input: every problem becomes an [`IoError`] naming the
//! file and, where it applies, the line. Only regular files are read, at most
//! [`MAX_INPUT_BYTES`](crate::files::MAX_INPUT_BYTES) of them. Writers go through temporary files
//! and renames ([`AtomicBatch`]), so a failed write never leaves half a mesh where a good one
//! was, nor an OBJ without its `.mtl`.

mod atomic;
mod error;
mod obj;
mod ply;

pub use atomic::{AtomicBatch, sweep_stale_temporaries, write_atomically};
pub use error::IoError;
pub use obj::{
    ObjReport, layer_materials, parse_obj, write_mtl, write_obj, write_obj_with_materials,
};
pub use ply::{parse_ply, write_ply};

use std::path::Path;

use crate::mesh::Mesh;

/// File formats by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Obj,
    Ply,
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
            _ => Err(IoError::UnsupportedFormat {
                path: path.display().to_string(),
            }),
        }
    }
}

/// What a lenient load found besides the mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadNotes {
    /// Vertices with a non-finite coordinate, and the first such line (OBJ).
    pub non_finite_vertices: usize,
    pub first_non_finite_line: Option<usize>,
}

/// Reads a mesh and checks it: malformed files, non-finite values and broken meshes are errors.
pub fn read_mesh(path: &Path) -> Result<Mesh, IoError> {
    let format = Format::of_path(path)?;
    let bytes = read_bytes(path)?;
    read_mesh_bytes(&bytes, format, &path.display().to_string())
}

/// [`read_mesh`] on bytes already in memory (`name` is used in messages).
pub fn read_mesh_bytes(bytes: &[u8], format: Format, name: &str) -> Result<Mesh, IoError> {
    let (mesh, notes) = load_mesh_bytes(bytes, format, name)?;
    if notes.non_finite_vertices > 0 {
        return Err(IoError::Parse {
            path: name.to_string(),
            line: notes.first_non_finite_line,
            message: format!(
                "{} vertices have a non-finite coordinate (NaN or infinity)",
                notes.non_finite_vertices
            ),
        });
    }
    mesh.validate()
        .map_err(|source| IoError::mesh(name.to_string(), source, &mesh))?;
    Ok(mesh)
}

/// Reads a mesh that is well-formed as a file and as a manifold surface, but lets non-finite
/// or out-of-range values through (counted in the notes) so that `slayer check` can report them.
pub fn load_mesh(path: &Path) -> Result<(Mesh, LoadNotes), IoError> {
    let format = Format::of_path(path)?;
    let bytes = read_bytes(path)?;
    load_mesh_bytes(&bytes, format, &path.display().to_string())
}

/// [`load_mesh`] on bytes already in memory.
pub fn load_mesh_bytes(
    bytes: &[u8],
    format: Format,
    name: &str,
) -> Result<(Mesh, LoadNotes), IoError> {
    match format {
        Format::Obj => {
            let (mesh, report) = parse_obj(bytes, name)?;
            Ok((
                mesh,
                LoadNotes {
                    non_finite_vertices: report.non_finite_vertices,
                    first_non_finite_line: report.first_non_finite_line,
                },
            ))
        }
        Format::Ply => {
            let mesh = parse_ply(bytes, name)?;
            let non_finite = mesh.positions().iter().filter(|p| !p.is_finite()).count();
            Ok((
                mesh,
                LoadNotes {
                    non_finite_vertices: non_finite,
                    first_non_finite_line: None,
                },
            ))
        }
    }
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
/// one unit.
pub fn stage_mesh(batch: &mut AtomicBatch, mesh: &Mesh, path: &Path) -> Result<(), IoError> {
    match Format::of_path(path)? {
        Format::Ply => batch.stage(path, &encode_mesh(mesh, Format::Ply)),
        Format::Obj => {
            let library = path.with_extension("mtl");
            let library_name = library
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "materials.mtl".into());
            let mut obj = Vec::new();
            let mut mtl = Vec::new();
            // Writing into a Vec cannot fail.
            let _ = write_obj_with_materials(mesh, &mut obj, Some(&library_name));
            let _ = write_mtl(mesh, &mut mtl);
            batch.stage(path, &obj)?;
            batch.stage(&library, &mtl)
        }
    }
}
