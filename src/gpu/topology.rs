//! The mesh's connectivity packed into one `u32` buffer, the form the proximity and normal
//! kernels read. One buffer rather than two or three keeps those kernels within few storage
//! bindings, and it is the one array those kernels page (`super::pages`) when it passes a
//! binding's limit. The connectivity changes only when remeshing does, so it is uploaded once
//! per stroke.
//!
//! Layout: face `f` is words `4f..4f + 4` = (a, b, c, layer), dead faces included so that face
//! ids index directly. From `vertex_faces_base` on, the vertex→faces rows in CSR form:
//! `vertex_count + 1` starts, absolute indices into the same buffer, then the face ids. Each
//! row lists the vertex's faces in fan order ([`Mesh::faces_around`]), so that normals sum in
//! the order the CPU's do; dead and isolated vertices have empty rows.

use super::{GpuContext, GpuError};
use crate::mesh::{INVALID, Mesh};

/// Words per face in the packed topology.
pub const FACE_WORDS: usize = 4;

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PackedTopology {
    pub words: Vec<u32>,
    pub vertex_faces_base: u32,
}

impl PackedTopology {
    pub fn of(mesh: &Mesh) -> PackedTopology {
        let (vertex_count, face_count) = (mesh.vertex_count(), mesh.face_count());
        let base = FACE_WORDS * face_count;
        let mut words = Vec::with_capacity(base + vertex_count + 1 + 3 * face_count);
        for (tri, &layer) in mesh.faces().iter().zip(mesh.face_layers()) {
            words.extend_from_slice(tri);
            words.push(layer);
        }
        // Starts are filled in as the rows are written after them.
        words.resize(base + vertex_count + 1, 0);
        for v in 0..vertex_count {
            words[base + v] = words.len() as u32;
            if mesh.adjacency().vertex_corner[v] != INVALID {
                words.extend(mesh.faces_around(v as u32));
            }
        }
        words[base + vertex_count] = words.len() as u32;
        PackedTopology {
            words,
            vertex_faces_base: base as u32,
        }
    }

    /// Faces around `vertex`, as the kernels read them.
    pub fn faces_of(&self, vertex: u32) -> &[u32] {
        let row = self.vertex_faces_base as usize + vertex as usize;
        &self.words[self.words[row] as usize..self.words[row + 1] as usize]
    }

    /// A read-only storage buffer of the words, bound page by page.
    pub fn upload(&self, gpu: &GpuContext) -> Result<wgpu::Buffer, GpuError> {
        gpu.check_paged("mesh topology", self.words.len())?;
        Ok(gpu.storage_buffer("mesh topology", &self.words, false))
    }
}
