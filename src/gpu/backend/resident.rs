//! The copy of the mesh that stays on the GPU between steps ([`Resident`]), and how it is kept
//! current:
//! - everything is uploaded once, with room (an eighth more vertices and faces, a quarter more
//!   row words: [`vertex_capacity`], [`face_capacity`]), and again only when the mesh changed
//!   behind the kernels' back or outgrew the room;
//! - positions, normals: after a step only the rows the pipeline reports (`moved`,
//!   `normals_changed`) are sent;
//! - after remeshing (`remeshed`), the rows of the vertices it changed — positions, normals,
//!   flags, layers, smoothing neighbours, faces and the faces around them — are patched in
//!   place (`crate::gpu::rows` keeps variable-length rows patchable), in one upload;
//! - flags alone: in full when they changed (masking between strokes; painting changes BRDFs,
//!   which the GPU does not keep).

use super::GpuKernels;
use super::hashed::{Hashed, TableUse};
use crate::gpu::reusable::{Patches, upload_rows};
use crate::gpu::{
    FACE_WORDS, GpuContext, GpuError, GpuSelection, PackedTopology, SlottedRows,
    SmoothingNeighbours, TopologyLayout, VertexBuffers, smoothing_neighbours,
};
use crate::mesh::{Mesh, MeshVersion};
use crate::pipeline::Uploads;

/// Rows every per-vertex buffer holds for a mesh of `count` vertices: an eighth more (and a
/// few thousand), so that the vertices remeshing adds are written into place; a mesh that
/// outgrows them is uploaded afresh. Sculpting adds vertices where strokes stretch the surface,
/// a few thousand a stroke on the benchmark scenes.
pub fn vertex_capacity(count: usize) -> usize {
    count + count / 8 + 4096
}

/// Faces the packed topology has room for, as [`vertex_capacity`] (twice as many faces as
/// vertices on a closed surface).
pub fn face_capacity(count: usize) -> usize {
    count + count / 8 + 8192
}

/// The packed topology on the GPU and where its parts lie.
pub(super) struct ResidentTopology {
    pub(super) buffer: wgpu::Buffer,
    pub(super) layout: TopologyLayout,
}

/// What lives on the GPU between steps.
pub(super) struct Resident {
    pub(super) version: MeshVersion,
    /// Rows of every per-vertex buffer (at least `vertices.count`).
    pub(super) capacity: usize,
    pub(super) vertices: VertexBuffers,
    pub(super) normals: wgpu::Buffer,
    /// Smooth's neighbours: per vertex (start, length), and the rows (paged).
    pub(super) neighbour_table: wgpu::Buffer,
    pub(super) neighbours: wgpu::Buffer,
    neighbour_rows: SlottedRows,
    pub(super) selection: GpuSelection,
    /// Built when first needed.
    pub(super) topology: Option<ResidentTopology>,
    /// Per vertex: pulled back in the last proximity pass (zero between steps).
    pub(super) marks: wgpu::Buffer,
    pub(super) hashed: Option<Hashed>,
    layer_count: usize,
}

impl Resident {
    /// Everything uploaded afresh (within our memory budget), with room to grow; the hash
    /// table and topology follow when first needed.
    fn upload(gpu: &GpuContext, mesh: &Mesh) -> Result<Resident, GpuError> {
        gpu.check_budget(resident_bytes(mesh))?;
        let count = mesh.vertex_count();
        // As much room as the bindings allow, and never less than the mesh needs.
        let fits = (gpu.limits.max_storage_buffer_binding_size / 12) as usize;
        let capacity = vertex_capacity(count).min(fits).max(count);
        let vertices = VertexBuffers::with_room(
            gpu,
            mesh.positions(),
            mesh.vertex_layers(),
            flag_bits(mesh),
            capacity,
        )?;
        let neighbours = smoothing_neighbours(mesh, capacity);
        gpu.check_paged("smoothing neighbours", neighbours.words.len())?;
        Ok(Resident {
            version: mesh.version(),
            capacity,
            normals: gpu.storage_buffer_with_room("normals", mesh.normals(), capacity),
            neighbour_table: gpu.storage_buffer_with_room(
                "neighbour rows",
                &neighbours.table(capacity),
                2 * capacity,
            ),
            neighbours: gpu.storage_buffer_with_room("neighbours", &neighbours.words, 0),
            neighbour_rows: neighbours.rows,
            selection: GpuSelection::new(gpu, capacity.max(1))?,
            topology: None,
            marks: gpu.output_buffer::<u32>("proximity marks", capacity),
            hashed: None,
            layer_count: mesh.layer_count(),
            vertices,
        })
    }

    /// Sends what remeshing changed — the rows of `changed` (ascending, every vertex added
    /// since among them) in every per-vertex array, the neighbour and topology rows, the faces
    /// around them — into room left for it. `false` when the mesh outgrew the room (upload
    /// afresh). The changed vertices go into the hash table's overlay (or, past its limit, the
    /// table is rebuilt at its next use).
    fn patch(&mut self, gpu: &GpuContext, mesh: &Mesh, changed: &[u32]) -> bool {
        if mesh.vertex_count() > self.capacity || mesh.layer_count() != self.layer_count {
            return false;
        }
        let mut patches = Patches::default();
        patches.rows(&self.vertices.flags, flag_bits(mesh), changed);
        patches.rows(&self.vertices.layers, mesh.vertex_layers(), changed);
        patches.rows(&self.vertices.positions, mesh.positions(), changed);
        patches.rows(&self.normals, mesh.normals(), changed);
        let buffers = (&self.neighbour_table, &self.neighbours);
        if !SmoothingNeighbours::patch(
            &mut self.neighbour_rows,
            mesh,
            changed,
            buffers,
            &mut patches,
        ) {
            return false;
        }
        patches.submit(gpu);
        // What remeshing changed goes into the hash table's overlay; the main table stays.
        let filed = self
            .hashed
            .as_mut()
            .is_none_or(|h| h.refile(gpu, mesh, changed));
        if !filed {
            // Rebuilt at the next use.
            self.hashed = None;
        }
        if let Some(t) = &mut self.topology {
            let mut topology = Patches::default();
            let fits = t.layout.patch(mesh, changed, &t.buffer, &mut topology);
            if fits {
                topology.submit(gpu);
            } else {
                // Packed afresh when next needed.
                self.topology = None;
            }
        }
        self.vertices.count = mesh.vertex_count();
        true
    }

    /// Reads the copy back and compares it with `mesh` row by row (positions, normals, flags,
    /// layers bit for bit; neighbour and face rows; the faces): `Err` names the first
    /// difference. For tests of the patching; a read-back of everything, so not for the loop.
    pub(super) fn check(&self, gpu: &GpuContext, mesh: &Mesh) -> Result<(), String> {
        let n = mesh.vertex_count();
        if self.vertices.count != n {
            return Err(format!(
                "{} vertices on the GPU, {n} in the mesh",
                self.vertices.count
            ));
        }
        let read = |buffer: &wgpu::Buffer, count: usize| -> Result<Vec<u32>, String> {
            gpu.read_buffer::<u32>(buffer, count)
                .map_err(|e| e.to_string())
        };
        let same = |what: &str, gpu: Vec<u32>, mesh: &[u32], per_vertex: usize| match gpu
            .iter()
            .zip(mesh)
            .position(|(a, b)| a != b)
        {
            None => Ok(()),
            Some(i) => Err(format!("{what} of vertex {} differ", i / per_vertex)),
        };
        let words = |v: &[glam::Vec3]| bytemuck::cast_slice::<glam::Vec3, u32>(v).to_vec();
        same(
            "positions",
            read(&self.vertices.positions, 3 * n)?,
            &words(mesh.positions()),
            3,
        )?;
        same(
            "normals",
            read(&self.normals, 3 * n)?,
            &words(mesh.normals()),
            3,
        )?;
        same("flags", read(&self.vertices.flags, n)?, flag_bits(mesh), 1)?;
        same(
            "layers",
            read(&self.vertices.layers, n)?,
            mesh.vertex_layers(),
            1,
        )?;
        let table = read(&self.neighbour_table, 2 * n)?;
        let neighbours = read(&self.neighbours, (self.neighbours.size() / 4) as usize)?;
        let mut expected = Vec::new();
        let row = |table: &[u32], words: &[u32], v: usize| -> Vec<u32> {
            let (start, len) = (table[2 * v] as usize, table[2 * v + 1] as usize);
            words.get(start..start + len).unwrap_or_default().to_vec()
        };
        for v in 0..n {
            expected.clear();
            crate::gpu::deform::neighbour_row(mesh, v as u32, &mut expected);
            if row(&table, &neighbours, v) != expected {
                return Err(format!("smoothing neighbours of vertex {v} differ"));
            }
        }
        if let Some(hashed) = &self.hashed {
            hashed.check(gpu, mesh)?;
        }
        let Some(topology) = &self.topology else {
            return Ok(());
        };
        let words = read(&topology.buffer, (topology.buffer.size() / 4) as usize)?;
        for (f, tri) in mesh.faces().iter().enumerate() {
            let packed = &words[FACE_WORDS * f..FACE_WORDS * f + 3];
            if !mesh.is_face_dead(f) && packed != tri {
                return Err(format!("face {f} differs"));
            }
        }
        let base = topology.layout.vertex_rows_base as usize;
        for v in 0..n {
            expected.clear();
            crate::gpu::topology::faces_row(mesh, v as u32, &mut expected);
            if row(&words[base..], &words, v) != expected {
                return Err(format!("faces of vertex {v} differ"));
            }
        }
        Ok(())
    }

    /// Uploads the packed topology (with room) if it is not resident yet: the proximity
    /// passes and the filter read it.
    pub(super) fn ensure_topology(
        &mut self,
        gpu: &GpuContext,
        mesh: &Mesh,
    ) -> Result<(), GpuError> {
        if self.topology.is_none() {
            let packed =
                PackedTopology::with_room(mesh, face_capacity(mesh.face_count()), self.capacity);
            self.topology = Some(ResidentTopology {
                buffer: packed.upload(gpu)?,
                layout: packed.layout,
            });
        }
        Ok(())
    }

    /// The hash table; [`GpuKernels::prepare`] builds it.
    pub(super) fn hashed(&self) -> &Hashed {
        self.hashed
            .as_ref()
            .expect("GpuKernels::prepare builds the hash table")
    }
}

/// What [`GpuKernels::sync`] brings up to date.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum CopyScope {
    Everything,
    /// All but the flags: what a viewport drawing from the copy reads. A mask stroke changes
    /// flags every sample, and the whole flag buffer need not follow each of its updates.
    Geometry,
}

/// What a mesh keeps resident on the GPU, in bytes, with the room it is allocated with
/// ([`vertex_capacity`], [`face_capacity`], the slotted rows' spare words): per vertex of room
/// positions, hashed positions and normals (12 bytes each), layer, flags, marks, overlay marks,
/// selection entry (8), hash keys and entries, up to four table slots (the table has a power of
/// two at least twice the vertices); two slotted rows — smoothing neighbours and faces — each a
/// (start, length) entry and about six words, one of room, a quarter spare; per face of room
/// its four packed words. Per-step buffers (a selection's worth) are not counted.
pub fn resident_bytes(mesh: &Mesh) -> u64 {
    let v = vertex_capacity(mesh.vertex_count()) as u64;
    let f = face_capacity(mesh.face_count()) as u64;
    let row_words = 2 + (6 + 1) * 5 / 4;
    v * (3 * 12 + 4 + 4 + 4 + 4 + 8 + 4 + 4 + 4 * 4 + 2 * 4 * row_words) + f * 4 * 4
}

impl GpuKernels {
    /// Brings the GPU copy up to date with `mesh` and makes its hash table, of `cell` sized
    /// cells, fresh enough for `table_use` (rebuilt when missing or drifted too far). A free
    /// function of the fields it needs, so that callers keep the step buffers borrowed beside
    /// what it returns.
    pub(super) fn prepare<'a>(
        gpu: &GpuContext,
        (resident, uploads): (&'a mut Option<Resident>, &mut Uploads),
        mesh: &Mesh,
        cell: f32,
        table_use: TableUse,
    ) -> Result<&'a mut Resident, GpuError> {
        let r = GpuKernels::sync(gpu, (resident, uploads), mesh, CopyScope::Everything)?;
        let vertices = (&r.vertices, r.capacity);
        Hashed::refresh(&mut r.hashed, gpu, uploads, mesh, vertices, cell, table_use)?;
        Ok(r)
    }

    /// Brings the GPU copy up to date with `mesh`, within `scope`.
    pub(super) fn sync<'a>(
        gpu: &GpuContext,
        (resident, uploads): (&'a mut Option<Resident>, &mut Uploads),
        mesh: &Mesh,
        scope: CopyScope,
    ) -> Result<&'a mut Resident, GpuError> {
        let version = mesh.version();
        let fits = resident.as_ref().is_some_and(|r| {
            r.version.topology == version.topology
                && r.vertices.count == mesh.vertex_count()
                && r.layer_count == mesh.layer_count()
        });
        if !fits {
            uploads.whole += 1;
            let fresh = Resident::upload(gpu, mesh)?;
            return Ok(resident.insert(fresh));
        }
        let Some(r) = resident.as_mut() else {
            unreachable!("a mesh that fits is resident");
        };
        if r.version.positions != version.positions {
            // Moved by something that did not say what: send everything, and file the
            // vertices anew (how far they went is unknown).
            let positions = bytemuck::cast_slice(mesh.positions());
            gpu.queue.write_buffer(&r.vertices.positions, 0, positions);
            gpu.queue
                .write_buffer(&r.normals, 0, bytemuck::cast_slice(mesh.normals()));
            r.hashed = None;
        }
        let flags = match scope {
            CopyScope::Everything if r.version.flags != version.flags => {
                gpu.queue
                    .write_buffer(&r.vertices.flags, 0, bytemuck::cast_slice(flag_bits(mesh)));
                version.flags
            }
            CopyScope::Everything => version.flags,
            // Left for the next stroke's own sync, as the version says.
            CopyScope::Geometry => r.version.flags,
        };
        r.version = MeshVersion { flags, ..version };
        Ok(r)
    }

    /// Sends the rows the pipeline changed, and notes how far they may have drifted.
    pub(super) fn gpu_moved(&mut self, mesh: &Mesh, vertices: &[u32], max_move: f32) {
        let Some(r) = self.resident.as_mut() else {
            return;
        };
        upload_rows(&self.gpu, &r.vertices.positions, mesh.positions(), vertices);
        let filed = std::mem::take(&mut self.taken_filed);
        if let Some(h) = r.hashed.as_mut() {
            h.note_moved(vertices, max_move, mesh.vertex_count(), filed);
        }
        r.version.positions = mesh.version().positions;
    }

    /// Patches the GPU copy after remeshing, when it was current before (`since`); otherwise,
    /// or when the mesh outgrew the room left, the next call uploads it afresh.
    pub(super) fn gpu_remeshed(&mut self, mesh: &Mesh, since: MeshVersion, changed: &[u32]) {
        let Some(r) = self.resident.as_mut() else {
            return;
        };
        if r.version != since {
            return;
        }
        let mut rows = changed.to_vec();
        rows.extend(r.vertices.count as u32..mesh.vertex_count() as u32);
        rows.sort_unstable();
        rows.dedup();
        if r.patch(&self.gpu, mesh, &rows) {
            r.version = mesh.version();
            self.uploads.patched += 1;
            // Still a table: what remeshing changed went into its overlay.
            self.uploads.overlay_filings += r.hashed.is_some() as usize;
        } else {
            self.resident = None;
        }
    }

    pub(super) fn gpu_normals_changed(&mut self, mesh: &Mesh, vertices: &[u32]) {
        if let Some(r) = self.resident.as_ref() {
            upload_rows(&self.gpu, &r.normals, mesh.normals(), vertices);
        }
    }
}

/// Puts the GPU's rows of `vertices` — positions, and the normals of every corner of the faces
/// around them, which `moved_normals` may have rewritten — back to the mesh's, in one upload.
pub(super) fn put_back_rows(
    gpu: &GpuContext,
    resident: Option<&Resident>,
    mesh: &Mesh,
    vertices: &[u32],
) {
    let Some(r) = resident else {
        return;
    };
    let mut corners: Vec<u32> = vertices
        .iter()
        .flat_map(|&v| mesh.faces_around(v).flat_map(|f| mesh.faces()[f as usize]))
        .collect();
    corners.sort_unstable();
    corners.dedup();
    let mut patches = Patches::default();
    patches.rows(&r.vertices.positions, mesh.positions(), vertices);
    patches.rows(&r.normals, mesh.normals(), &corners);
    patches.submit(gpu);
}

/// The vertex flags as the kernels read them, one `u32` each.
fn flag_bits(mesh: &Mesh) -> &[u32] {
    bytemuck::cast_slice(mesh.flags())
}
