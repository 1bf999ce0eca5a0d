use thiserror::Error;

use crate::mesh::{Mesh, MeshError};

/// Why a mesh file could not be read or written. Displayed on one line: `file:line: problem`.
#[derive(Debug, Error)]
pub enum IoError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "{path}: unsupported file type (expected .obj, .ply, .stl, .glb, .gltf or, where a session fits, .slayer)"
    )]
    UnsupportedFormat { path: String },
    #[error("{path}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        path: String,
        line: Option<usize>,
        message: String,
    },
    #[error("{path}: {source}{hint}")]
    Mesh {
        path: String,
        #[source]
        source: MeshError,
        /// Where the named vertices are, since file order and mesh order can differ.
        hint: String,
    },
}

impl IoError {
    /// A parse error; control characters in `message` (which may quote the file) are escaped.
    pub fn parse(path: &str, line: Option<usize>, message: impl Into<String>) -> IoError {
        IoError::Parse {
            path: path.to_string(),
            line,
            message: crate::files::escape(&message.into()).into_owned(),
        }
    }

    /// A mesh error with the positions of the vertices it names.
    pub fn mesh(path: String, source: MeshError, mesh: &Mesh) -> IoError {
        IoError::building(&path, source, mesh.positions())
    }

    /// A mesh error found while building, before a `Mesh` exists; positions give the hint.
    pub fn building(path: &str, source: MeshError, positions: &[glam::Vec3]) -> IoError {
        let hint = mesh_error_vertices(&source)
            .iter()
            .filter_map(|&v| positions.get(v as usize).map(|p| (v, p)))
            .map(|(v, p)| format!("vertex {v} at ({}, {}, {})", p.x, p.y, p.z))
            .collect::<Vec<_>>()
            .join(", ");
        IoError::Mesh {
            path: path.to_string(),
            source,
            hint: if hint.is_empty() {
                hint
            } else {
                format!(" [{hint}]")
            },
        }
    }
}

fn mesh_error_vertices(error: &MeshError) -> Vec<u32> {
    match *error {
        MeshError::NonManifoldEdge { a, b, .. }
        | MeshError::InconsistentOrientation { a, b, .. } => {
            vec![a, b]
        }
        MeshError::NonManifoldVertex { vertex }
        | MeshError::IsolatedVertex { vertex }
        | MeshError::DegenerateFace { vertex, .. } => vec![vertex],
        _ => Vec::new(),
    }
}
