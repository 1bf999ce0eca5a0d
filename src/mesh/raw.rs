//! A mesh's arrays as they are in memory, dead rows and adjacency included, for slayer's own
//! session file: a history recorded on a mesh replays only on that exact layout, which a
//! compacting format (PLY, OBJ) does not keep.

use thiserror::Error;

use super::{CornerTable, Mesh, MeshError, MeshVersion};
use crate::codec::{DecodeError, Reader, Writer};

/// Why stored arrays are not a mesh.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum RawMeshError {
    #[error(transparent)]
    Decode(#[from] DecodeError),
    #[error("the stored mesh is broken: {0}")]
    Invalid(#[from] MeshError),
}

impl Mesh {
    /// Appends every array of the mesh, as it is.
    pub fn write_raw(&self, out: &mut Writer) {
        out.array(&self.positions);
        out.array(&self.normals);
        out.array(&self.brdfs);
        out.array(&self.vertex_layers);
        out.array(&self.flags);
        out.array(&self.faces);
        out.array(&self.face_layers);
        out.array(&self.adjacency.opposite);
        out.array(&self.adjacency.vertex_corner);
        out.strings(&self.layer_names);
    }

    /// Reads what [`Mesh::write_raw`] wrote and checks it as [`Mesh::validate`] does, so a
    /// forged file gives an error naming the broken element, never a mesh the engine trips on.
    pub fn read_raw(input: &mut Reader) -> Result<Mesh, RawMeshError> {
        let mut mesh = Mesh {
            positions: input.array("positions")?,
            normals: input.array("normals")?,
            brdfs: input.array("brdfs")?,
            vertex_layers: input.array("vertex layers")?,
            flags: input.array("flags")?,
            faces: input.array("faces")?,
            face_layers: input.array("face layers")?,
            adjacency: CornerTable {
                opposite: input.array("opposite corners")?,
                vertex_corner: input.array("vertex corners")?,
            },
            layer_names: input.strings("layer names")?,
            version: MeshVersion::fresh(),
        };
        mesh.validate()?;
        mesh.reserve_for_edits();
        Ok(mesh)
    }
}
