//! The mesh's connectivity packed into one `u32` buffer, the form the proximity and normal
//! kernels read. One buffer rather than two or three keeps those kernels within few storage
//! bindings, and it is the one array those kernels page (`super::pages`) when it passes a
//! binding's limit. Remeshing changes it around each stroke; [`TopologyLayout::patch`] sends
//! those rows alone.
//!
//! Layout, with room for `face_capacity` faces and `vertex_capacity` vertices: face `f` is words
//! `4f..4f + 4` = (a, b, c, layer), dead faces included so that face ids index directly. From
//! `vertex_rows_base` on, per vertex its row's absolute start and length (`super::rows`), then
//! the rows: each vertex's faces in fan order ([`Mesh::faces_around`]; normals are summed
//! order-free, `shared/order_free.wgsl`); dead and isolated vertices have empty rows.

use super::reusable::Patches;
use super::rows::SlottedRows;
use super::{GpuContext, GpuError};
use crate::abi::FACE_WORDS;
use crate::mesh::{INVALID, Mesh};

/// Where everything lives in the packed topology; kept beside its buffer to patch it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopologyLayout {
    pub face_capacity: usize,
    pub vertex_capacity: usize,
    /// Word where the per-vertex (start, length) entries begin.
    pub vertex_rows_base: u32,
    pub rows: SlottedRows,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PackedTopology {
    pub words: Vec<u32>,
    pub layout: TopologyLayout,
}

impl PackedTopology {
    /// Packed with no room to spare.
    pub fn of(mesh: &Mesh) -> PackedTopology {
        PackedTopology::with_room(mesh, mesh.face_count(), mesh.vertex_count())
    }

    /// Packed with room for `face_capacity` faces and `vertex_capacity` vertices (at least the
    /// mesh's), so that remeshing can add some without a fresh layout.
    pub fn with_room(mesh: &Mesh, face_capacity: usize, vertex_capacity: usize) -> PackedTopology {
        let (vertex_count, face_count) = (mesh.vertex_count(), mesh.face_count());
        let (face_capacity, vertex_capacity) = (
            face_capacity.max(face_count),
            vertex_capacity.max(vertex_count),
        );
        let vertex_rows_base = FACE_WORDS * face_capacity;
        let rows_base = vertex_rows_base + 2 * vertex_capacity;
        let mut words = Vec::with_capacity(rows_base + 4 * face_count);
        for (tri, &layer) in mesh.faces().iter().zip(mesh.face_layers()) {
            words.extend_from_slice(tri);
            words.push(layer);
        }
        words.resize(rows_base, 0);
        let (rows, row_words) = SlottedRows::build(
            vertex_count,
            vertex_capacity - vertex_count,
            rows_base as u32,
            |v, row| faces_row(mesh, v, row),
        );
        words[vertex_rows_base..vertex_rows_base + rows.table.len()].copy_from_slice(&rows.table);
        words.extend_from_slice(&row_words);
        PackedTopology {
            words,
            layout: TopologyLayout {
                face_capacity,
                vertex_capacity,
                vertex_rows_base: vertex_rows_base as u32,
                rows,
            },
        }
    }

    /// Faces around `vertex`, as the kernels read them.
    pub fn faces_of(&self, vertex: u32) -> &[u32] {
        let (start, len) = self.layout.rows.row(vertex);
        &self.words[start as usize..(start + len) as usize]
    }

    /// A read-only storage buffer of the words, bound page by page (the host patches it).
    pub fn upload(&self, gpu: &GpuContext) -> Result<wgpu::Buffer, GpuError> {
        gpu.check_paged("mesh topology", self.words.len())?;
        Ok(gpu.storage_buffer("mesh topology", &self.words, true))
    }
}

/// `vertex`'s faces in fan order (none when dead or isolated).
pub(super) fn faces_row(mesh: &Mesh, vertex: u32, row: &mut Vec<u32>) {
    if mesh.adjacency().vertex_corner[vertex as usize] != INVALID {
        row.extend(mesh.faces_around(vertex));
    }
}

impl TopologyLayout {
    /// Queues into `patches` what changed in `mesh` since `buffer` was packed, given every vertex
    /// whose faces changed (`changed`, ascending; vertices added since must be among them) —
    /// their rows, and the words of the faces around them. `false` when it no longer fits the
    /// room (pack it afresh).
    pub fn patch<'a>(
        &mut self,
        mesh: &Mesh,
        changed: &[u32],
        buffer: &'a wgpu::Buffer,
        patches: &mut Patches<'a>,
    ) -> bool {
        if mesh.face_count() > self.face_capacity || mesh.vertex_count() > self.vertex_capacity {
            return false;
        }
        let mut faces: Vec<u32> = changed
            .iter()
            .filter(|&&v| mesh.adjacency().vertex_corner[v as usize] != INVALID)
            .flat_map(|&v| mesh.faces_around(v))
            .collect();
        faces.sort_unstable();
        faces.dedup();
        for &f in &faces {
            let [a, b, c] = mesh.faces()[f as usize];
            let words = [a, b, c, mesh.face_layers()[f as usize]];
            patches.write(buffer, FACE_WORDS * f as usize, &words);
        }
        let table = (buffer, self.vertex_rows_base as usize);
        self.rows.patch(
            changed,
            |v, row| faces_row(mesh, v, row),
            (table, buffer),
            patches,
        )
    }
}
