//! The GPU's side of a brush step behind the pipeline's [`StepKernels`] seam: selection,
//! deformation and the proximity passes (the collision response's first phase) run as WGSL
//! kernels over a copy of the mesh that stays on the GPU. The pipeline keeps the loop, the
//! exact backstop and remeshing on the CPU, and tells the kernels what it changed.
//!
//! What stays resident, and when it is refreshed:
//! - everything is uploaded once, with room (an eighth more vertices and faces, a quarter more
//!   row words), and again only when the mesh changed behind the kernels' back or outgrew the
//!   room;
//! - positions, normals: after a step only the rows the pipeline reports (`moved`,
//!   `normals_changed`) are sent;
//! - after remeshing (`remeshed`), the rows of the vertices it changed — positions, normals,
//!   flags, layers, smoothing neighbours, faces and the faces around them — are patched in
//!   place (`super::rows` keeps variable-length rows patchable), in one upload;
//! - flags alone: in full when they changed (masking between strokes; painting changes BRDFs,
//!   which the GPU does not keep);
//! - the hash table: built once; the vertices moved or changed since are filed in its overlay
//!   (`super::overlay`) and refiled when they drift farther than the use tolerates — queries
//!   grow their reach by the drift until then (`select`, `proximity`); rebuilt over every
//!   vertex only when the overlay passes its limit; between samples run ahead, the GPU files
//!   each sample's moved vertices in the overlay itself, and the host refiles after;
//! - per-step buffers: grown when a step needs more, never reallocated otherwise.
//!
//! A step is one submission with one blocking read-back where it can be: selection and
//! deformation (the selection's count, a guessed head of the list and its targets together; at
//! a sample's start also the brush frame, summed by `brush_frame` and read by `deform` on the
//! GPU), then `moving_entries` (the moving list and exclusion rings from the selection list)
//! and the whole Jacobi loop of proximity passes with the backstop's filter (targets placed,
//! passes sized by the GPU through indirect dispatch, final positions gathered), the passes'
//! reach sized for an assumed longest move ([`AHEAD_MOVE_GROWTH`] times the last). A step
//! that moves farther, or takes several steps, or outgrows the guessed list or the rings'
//! room, drops those passes and runs them in a second submission over the host's entries once
//! its moves are known. The proximity passes run here on hardware adapters; see
//! [`GpuKernels::new`]. There, several samples of a stroke run ahead in one submission
//! (`run_ahead`), while the pipeline takes them as predicted.
//!
//! A GPU that fails mid-stroke (device lost, an allocation refused, a buffer past the
//! adapter's limits, a mesh past our memory budget) is not fatal: the kernels keep why and finish on the CPU, and the mesh —
//! which the CPU writes — is untouched by the failure.

use glam::Vec3;

use super::reusable::{Patches, ReusableBuffer, upload_rows};
use super::{
    APPLY_WORKGROUP_SIZE, ApplyMode, ApplyMovesBuffers, ApplyParams, BackstopBuffers,
    BackstopParams, BrushSphere, BuiltEntryBuffers, DeformBuffers, EntryBuffers, FACE_WORDS,
    FRAME_WORKGROUP_SIZE, Filed, GateBuffers, GateStatus, GpuContext, GpuError, GpuHashTable,
    GpuOptions, GpuSelection, HashedVertices, MovingVertex, OverlayBuffers, PAIRS_GUESS,
    PROXIMITY_WORKGROUP_SIZE, PackedTopology, ProximityBuffers, ProximityParams, SELECTION_GUESS,
    SelectedVertex, SelectionBuffers, SlotBuffers, SlottedRows, SmoothingNeighbours, TableBuffers,
    TopologyLayout, VertexBuffers, Workgroups, backstop_params, check_invocations, deform_params,
    entry_params, frame_params, frame_sums_buffer, indirect_args_buffer, moved_edge_bound,
    moving_vertices, overlay_limit, overlay_table, pass_params, read_table, record_apply_moves,
    record_backstop, record_brush_frame, record_deform, record_dispatch_args, record_gate_check,
    record_gate_open, record_moving_entries, record_overlay_members, record_overlay_table,
    record_proximity, record_select, ring_bytes, smoothing_neighbours, table_size_for,
};
use crate::brush::{Dab, DabFrame};
use crate::grid::{cell_coordinates, hash_cell};

mod run_ahead;
use crate::collide::{Backstop, MAX_PASSES, Region, StepMoves, StrokeState, clamp_in_region};
use crate::cpu::FRAME_SUM_WORDS;
use crate::mesh::{Mesh, MeshVersion};
use crate::pipeline::step::{frame_flags, frame_of_sums, longest_move};
use crate::pipeline::{
    BackstopFilter, CallAt, CpuKernels, Deformed, FrameSource, GpuMemory, SampleProbe, StepKernels,
    Uploads,
};

/// The proximity passes rebuild the hash table once vertices may have drifted this many cells
/// from where they were filed. Queries grow by the drift, and the passes' work grows with the
/// cube of their reach: on lavapipe (plaster, 20K faces, steps of one edge length) keeping the
/// table for two steps made the passes 2.6 times dearer (22³ instead of 16³ cells per moving
/// vertex) while a rebuild is four passes over the vertices. So with the passes on the GPU the
/// table follows every step that moves vertices by half a cell or more.
const DRIFT_LIMIT_CELLS: f32 = 0.5;

/// Selection alone tolerates a drift of this share of the brush radius: its box grows by at
/// most half on each side (about twice the cells), while a rebuild passes over every vertex.
/// Plaster at 16M faces on lavapipe, selection and deformation on the GPU: rebuilding at every
/// half cell took 2,021 ms a sample (1.6 s a rebuild, nearly every step); without per-step
/// rebuilds, 312 ms.
const SELECT_DRIFT_SHARE: f32 = 0.25;

/// How the caller uses the hash table, and so how stale it may be.
#[derive(Debug, Clone, Copy)]
enum TableUse {
    /// Not at all (deformation): whatever table there is stays, stale or not.
    None,
    /// Any table, however old (the warm-up before a stroke).
    Present,
    /// Brush selection with this radius.
    Select { radius: f32 },
    /// The proximity passes.
    Proximity,
}

impl TableUse {
    /// The drift (world units) past which the table is rebuilt first; `None` when the caller
    /// does not read the table.
    fn drift_limit(self, cell: f32) -> Option<f32> {
        let least = DRIFT_LIMIT_CELLS * cell;
        match self {
            TableUse::None => None,
            TableUse::Present => Some(f32::INFINITY),
            TableUse::Select { radius } => Some((SELECT_DRIFT_SHARE * radius).max(least)),
            TableUse::Proximity => Some(least),
        }
    }
}

/// The table and the positions it was built from.
struct Hashed {
    table: GpuHashTable,
    /// Where each vertex was filed: at the build, or for the overlay's members at their filing.
    positions: wgpu::Buffer,
    /// Per vertex: its slot in the overlay + 1 (`super::overlay`), 0 when not filed there.
    marks: wgpu::Buffer,
    /// How far any vertex may have moved since it was filed.
    drift: f32,
    /// The vertices moved or changed since the build, filed apart (`super::overlay`).
    overlay: Option<Overlay>,
    /// Vertices moved since the last filing (unsorted, may repeat).
    moved: Vec<u32>,
    /// The GPU refiled the overlay since the host did (samples run ahead): `overlay.members`
    /// and the marks no longer say what it holds, so the host refiles before the next use.
    filed_on_gpu: bool,
    /// While the GPU's filing is in place and no sample run ahead was dropped since: how far
    /// any vertex may be from where it is filed — the drift the run's queries assumed, plus
    /// the moves taken since that the GPU did not file. `None` when unknown.
    gpu_drift: Option<f32>,
}

/// The overlay table and its members.
struct Overlay {
    /// Ascending vertex ids, as the host filed them; slot + 1 is each one's mark.
    members: Vec<u32>,
    table_size: u32,
    offsets: ReusableBuffer,
    entries: ReusableBuffer,
    /// The members in slots, for refiling on the GPU (`super::overlay`).
    slots: SlotBuffers,
}

impl Overlay {
    fn empty() -> Overlay {
        Overlay {
            members: Vec::new(),
            table_size: 0,
            offsets: ReusableBuffer::storage("overlay offsets"),
            entries: ReusableBuffer::storage("overlay entries"),
            slots: SlotBuffers::default(),
        }
    }
}

impl Hashed {
    /// Files every vertex that moved or changed since the main table was built — the
    /// overlay's members, the vertices moved since its filing (`moved`) and `changed` — in the
    /// overlay at its current position, and marks them: afterwards no vertex has drifted
    /// from where it is filed. O(those vertices), where a rebuild is O(every vertex). `false`
    /// when they pass [`overlay_limit`] (or the overlay's buffers the adapter's limits):
    /// rebuild the main table instead.
    fn refile(&mut self, gpu: &GpuContext, mesh: &Mesh, changed: &[u32]) -> bool {
        let overlay = self.overlay.get_or_insert_with(Overlay::empty);
        let mut members = std::mem::take(&mut self.moved);
        members.extend_from_slice(&overlay.members);
        members.extend_from_slice(changed);
        members.sort_unstable();
        members.dedup();
        if members.len() > overlay_limit(mesh.vertex_count()) {
            return false;
        }
        let table = overlay_table(mesh.positions(), &members, self.table.inv_cell_size);
        overlay.table_size = table.table_size() as u32;
        if overlay.offsets.upload(gpu, &table.offsets).is_err()
            || overlay.entries.upload(gpu, &table.entries).is_err()
        {
            return false;
        }
        let mut patches = Patches::default();
        patches.rows(&self.positions, mesh.positions(), &members);
        for (slot, &v) in members.iter().enumerate() {
            patches.write(&self.marks, v as usize, &[slot as u32 + 1]);
        }
        patches.submit(gpu);
        overlay.members = members;
        self.drift = 0.0;
        self.filed_on_gpu = false;
        self.gpu_drift = None;
        true
    }

    /// Makes the overlay ready to be refiled on the GPU in slots with room for `room`
    /// members, its table sized for them; the host's filing is then out of date until it
    /// refiles. Record [`Hashed::record_gpu_table`] before the overlay is next read.
    fn start_gpu_filing(&mut self, gpu: &GpuContext, room: usize) -> Result<(), GpuError> {
        self.filed_on_gpu = true;
        self.gpu_drift = Some(self.drift);
        let overlay = self.overlay.get_or_insert_with(Overlay::empty);
        let room = room.max(overlay.members.len());
        let table_size = table_size_for(room);
        overlay.slots.start(gpu, &overlay.members, room)?;
        // Grown buffers lose their contents: the table is rebuilt from the slots first.
        overlay.offsets.reserve(gpu, 4 * (table_size as u64 + 1))?;
        overlay.entries.reserve(gpu, 4 * room as u64)?;
        overlay.table_size = table_size;
        Ok(())
    }

    /// Records the rebuild of the overlay table from its slots ([`Hashed::start_gpu_filing`]).
    fn record_gpu_table(
        &self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let (Some(overlay), Some(table)) = (&self.overlay, self.overlay()) else {
            unreachable!("start_gpu_filing made the overlay");
        };
        let inv_cell_size = self.table.inv_cell_size;
        record_overlay_table(
            gpu,
            encoder,
            &overlay.slots,
            &self.positions,
            table.table,
            inv_cell_size,
        )
    }

    /// Records the filing of the entries of the first `slots` slots of `moving` that are away
    /// from their start in `positions` where they are, and the rebuild of the table.
    fn record_gpu_filing(
        &self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        positions: &wgpu::Buffer,
        (moving, slots): (&wgpu::Buffer, usize),
    ) -> Result<(), GpuError> {
        let Some(overlay) = &self.overlay else {
            unreachable!("start_gpu_filing made the overlay");
        };
        let filed = Filed {
            marks: &self.marks,
            filed_at: &self.positions,
        };
        record_overlay_members(
            gpu,
            encoder,
            (positions, moving, slots),
            &overlay.slots,
            filed,
        )?;
        self.record_gpu_table(gpu, encoder)
    }

    /// Reads the filing back and checks that queries find every live vertex of `mesh`: a
    /// marked one in the overlay bucket of where it is filed (its mark naming its slot when
    /// the host filed it), another in the main table's; and, while the host's filing is
    /// current, each filed within the drift of where it is.
    fn check(&self, gpu: &GpuContext, mesh: &Mesh) -> Result<(), String> {
        let n = mesh.vertex_count();
        let fail = |e: GpuError| e.to_string();
        let filed_at: Vec<Vec3> = gpu.read_buffer(&self.positions, n).map_err(fail)?;
        let marks: Vec<u32> = gpu.read_buffer(&self.marks, n).map_err(fail)?;
        let main = self.table.read(gpu).map_err(fail)?;
        let overlay = match &self.overlay {
            Some(o) => Some(
                read_table(gpu, (o.offsets.buffer(), o.entries.buffer()), o.table_size)
                    .map_err(fail)?,
            ),
            None => None,
        };
        let inv = self.table.inv_cell_size;
        for v in (0..n as u32).filter(|&v| !mesh.is_vertex_dead(v)) {
            let at = filed_at[v as usize];
            let (table, which) = match (&overlay, marks[v as usize]) {
                (_, 0) => (&main, "main table"),
                (Some(o), _) => (o, "overlay"),
                (None, _) => return Err(format!("vertex {v} is marked with no overlay")),
            };
            let bucket = hash_cell(cell_coordinates(at, inv), table.table_size() as u32);
            if !table.bucket(bucket).contains(&v) {
                return Err(format!("vertex {v} is not in its {which} bucket"));
            }
            let bound = match (self.filed_on_gpu, self.gpu_drift) {
                (false, _) => self.drift,
                (true, Some(bound)) => bound,
                (true, None) => continue,
            };
            let drift = at.distance(mesh.positions()[v as usize]);
            if drift > bound * (1.0 + 1e-5) + 1e-6 {
                return Err(format!(
                    "vertex {v} drifted {drift} from its filing, past {bound}"
                ));
            }
            if self.filed_on_gpu {
                continue;
            }
            if let (Some(o), m @ 1..) = (&self.overlay, marks[v as usize])
                && o.members.get(m as usize - 1) != Some(&v)
            {
                return Err(format!("the mark of vertex {v} names another's slot"));
            }
        }
        Ok(())
    }

    /// Notes that `vertices` moved by at most `max_move`: they are filed anew at the next
    /// refiling, and until then queries reach that much farther. `filed_on_gpu`: a sample run
    /// ahead that filed them there already.
    fn note_moved(
        &mut self,
        vertices: &[u32],
        max_move: f32,
        vertex_count: usize,
        filed_on_gpu: bool,
    ) {
        self.drift += max_move;
        if !filed_on_gpu && let Some(bound) = &mut self.gpu_drift {
            *bound += max_move;
        }
        self.moved.extend_from_slice(vertices);
        let limit = overlay_limit(vertex_count);
        if self.moved.len() > limit {
            self.moved.sort_unstable();
            self.moved.dedup();
            if self.moved.len() > limit {
                // Too many to file apart: stale for every use, so the next rebuilds.
                self.drift = f32::INFINITY;
            }
        }
    }

    /// The overlay as queries bind it.
    fn overlay(&self) -> Option<OverlayBuffers<'_>> {
        self.overlay.as_ref().map(|o| OverlayBuffers {
            table: TableBuffers {
                table_size: o.table_size,
                offsets: o.offsets.buffer(),
                entries: o.entries.buffer(),
            },
            marks: &self.marks,
        })
    }
}

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
struct ResidentTopology {
    buffer: wgpu::Buffer,
    layout: TopologyLayout,
}

/// What lives on the GPU between steps.
struct Resident {
    version: MeshVersion,
    /// Rows of every per-vertex buffer (at least `vertices.count`).
    capacity: usize,
    vertices: VertexBuffers,
    normals: wgpu::Buffer,
    /// Smooth's neighbours: per vertex (start, length), and the rows (paged).
    neighbour_table: wgpu::Buffer,
    neighbours: wgpu::Buffer,
    neighbour_rows: SlottedRows,
    selection: GpuSelection,
    /// Built when first needed.
    topology: Option<ResidentTopology>,
    /// Per vertex: pulled back in the last proximity pass (zero between steps).
    marks: wgpu::Buffer,
    hashed: Option<Hashed>,
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
    fn check(&self, gpu: &GpuContext, mesh: &Mesh) -> Result<(), String> {
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
            super::deform::neighbour_row(mesh, v as u32, &mut expected);
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
            super::topology::faces_row(mesh, v as u32, &mut expected);
            if row(&words[base..], &words, v) != expected {
                return Err(format!("faces of vertex {v} differ"));
            }
        }
        Ok(())
    }

    /// The hash table; [`GpuKernels::prepare`] builds it.
    /// Uploads the packed topology (with room) if it is not resident yet: the proximity
    /// passes and the filter read it.
    fn ensure_topology(&mut self, gpu: &GpuContext, mesh: &Mesh) -> Result<(), GpuError> {
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

    fn hashed(&self) -> &Hashed {
        self.hashed
            .as_ref()
            .expect("GpuKernels::prepare builds the hash table")
    }
}

/// Per-step buffers, reused from step to step.
struct StepBuffers {
    selected: ReusableBuffer,
    selection_count: wgpu::Buffer,
    targets: ReusableBuffer,
    moving: ReusableBuffer,
    /// Exclusion rings built by the host, one after another.
    rings: ReusableBuffer,
    /// Exclusion rings built by `moving_entries`, `RING_STRIDE` words a slot, and how many
    /// did not fit.
    ring_slots: ReusableBuffer,
    ring_overflows: wgpu::Buffer,
    /// Per entry: the last proximity pass's pull-back amount.
    pulls: ReusableBuffer,
    finals: ReusableBuffer,
    /// The backstop filter's undecided pairs, their count, and the room there is for them.
    pairs: ReusableBuffer,
    pair_count: wgpu::Buffer,
    pair_capacity: usize,
    next_count: wgpu::Buffer,
    pass_args: wgpu::Buffer,
    apply_args: wgpu::Buffer,
    /// The brush frame's sums, and its dispatch sized from the selection count.
    frame_sums: wgpu::Buffer,
    frame_args: wgpu::Buffer,
    /// A run's [`GateStatus`]: whether a sample has stopped it, the current sample's longest
    /// move (`longest_move`) and the run's edge bound (`moved_edges`).
    gate_status: wgpu::Buffer,
    /// The moving lists of a run's steps of one sample, one after another, for the normals
    /// after its last step.
    held_moving: ReusableBuffer,
}

impl StepBuffers {
    /// What the run's gate reads and writes for a step recorded into these buffers.
    fn gate<'b>(&'b self, r: &'b Resident) -> GateBuffers<'b> {
        GateBuffers {
            positions: &r.vertices.positions,
            selected: &r.selection.selected,
            selection_count: &r.selection.count,
            targets: self.targets.buffer(),
            ring_overflows: &self.ring_overflows,
            moving: self.moving.buffer(),
            status: &self.gate_status,
        }
    }

    fn new(gpu: &GpuContext) -> StepBuffers {
        StepBuffers {
            selected: ReusableBuffer::storage("selected"),
            selection_count: gpu.output_buffer::<u32>("selection count", 1),
            targets: ReusableBuffer::storage("targets"),
            moving: ReusableBuffer::storage("moving"),
            rings: ReusableBuffer::paged("exclusion rings"),
            ring_slots: ReusableBuffer::storage("exclusion ring slots"),
            ring_overflows: gpu.output_buffer::<u32>("ring overflows", 1),
            pulls: ReusableBuffer::storage("pull-back amounts"),
            finals: ReusableBuffer::storage("finals"),
            pairs: ReusableBuffer::storage("undecided pairs"),
            pair_count: gpu.output_buffer::<u32>("undecided pair count", 1),
            pair_capacity: PAIRS_GUESS,
            next_count: gpu.output_buffer::<u32>("next pass count", 1),
            pass_args: indirect_args_buffer(gpu, "proximity pass sizes"),
            apply_args: indirect_args_buffer(gpu, "apply pass sizes"),
            frame_sums: frame_sums_buffer(gpu),
            frame_args: indirect_args_buffer(gpu, "brush frame sizes"),
            gate_status: gpu.output_buffer::<GateStatus>("run gate status", 1),
            held_moving: ReusableBuffer::storage("moving lists of a sample's steps"),
        }
    }
}

pub struct GpuKernels {
    gpu: GpuContext,
    /// Size of the last selection: how much of the list to read back with its count.
    last_selection: usize,
    /// Whether the proximity passes run on the GPU (else on the CPU, `clamp_moves`).
    proximity_on_gpu: bool,
    /// Whether, after GPU proximity passes, the backstop's first round is filtered there too
    /// (else the CPU gathers the step's region and searches it).
    backstop_on_gpu: bool,
    /// Whether a step's proximity passes may run in the submission that selected and
    /// deformed (`select_deform_and_clamp`; [`GpuOptions::clamp_in_one_submission`]).
    clamp_ahead: bool,
    /// Whether, with those, several samples of a stroke run ahead in one submission
    /// (`run_ahead`; see [`GpuKernels::set_run_ahead`]).
    run_ahead: bool,
    resident: Option<Resident>,
    step: StepBuffers,
    /// Where every submission's results are copied to be mapped.
    readback: ReusableBuffer,
    /// Set once the GPU failed: why. Everything after runs on the CPU.
    failed: Option<String>,
    /// Test hook: fail as a lost device would after this many more GPU calls.
    fail_after: Option<usize>,
    uploads: Uploads,
    filter: BackstopFilter,
    /// The proximity passes a merged submission ran ahead of the pipeline's `clamp`.
    ahead: Option<ClampedAhead>,
    /// The longest move of the last deformation read back (zero before the first).
    last_move: f32,
    /// The step limit of the stroke, and the last sample start: the pipeline deforms its
    /// selection again at the first step of a sample of several, which then records the
    /// sample's steps and the samples after it in one run (`deform`).
    step_limit: Option<f32>,
    opened: Option<OpenedSample>,
    /// The planned sample that stopped the last run where a run starting at it would stop
    /// again: the pipeline's call for it runs alone.
    no_run_at: Option<usize>,
    /// The vertices the steps of the current sample taken from a run moved: the run
    /// recomputed their normals after the sample's last step, which go back with it.
    steps_taken: Vec<u32>,
    /// The samples the pipeline gave (`given`: those of its current call), the stroke's number
    /// of the first, and the index of the one after the last it took from a submission that
    /// ran several ahead.
    plan: Vec<SampleProbe>,
    plan_first: usize,
    plan_next: usize,
    /// How many samples the next run ahead records, and how many of the last run the pipeline
    /// took (`run_ahead`).
    run_length: usize,
    run_taken: usize,
    /// Samples run ahead in such a submission, waiting for the pipeline (`run_ahead`).
    queued: run_ahead::Queue,
    /// The vertices and final positions of the last step taken from passes run ahead, to see
    /// whether the pipeline kept them (`moved`).
    taken: Option<(Vec<u32>, Vec<Vec3>)>,
    /// The sample taken last was filed in the overlay on the GPU as it ran ahead.
    taken_filed: bool,
    /// Check the GPU's filing before the host replaces it (`set_check_filing`), and what the
    /// first check found wrong.
    check_filing: bool,
    filing_error: Option<String>,
    /// Read-backs the checks made, left out of [`Uploads::read_backs`].
    check_read_backs: usize,
}

/// A sample start the pipeline may go on to deform in several steps.
#[derive(Debug, Clone, Copy)]
struct OpenedSample {
    /// Its number in the stroke, to know the call for its first step.
    sample: usize,
    /// Where it is in the plan: the samples after it follow its steps in their run.
    planned: Option<usize>,
}

/// A merged submission's passes assume moves up to this many times the last step's longest.
const AHEAD_MOVE_GROWTH: f32 = 2.0;

/// A step's proximity passes and filter run in the submission that selected and deformed
/// (`GpuKernels::select_deform_and_clamp`), waiting for the pipeline to clamp these moves.
struct ClampedAhead {
    /// The selection (ascending) and its targets.
    vertices: Vec<u32>,
    targets: Vec<Vec3>,
    /// One per selected vertex.
    finals: Vec<Vec3>,
    backstop: Backstop,
}

impl GpuKernels {
    /// Kernels on `gpu` with the default [`GpuOptions`].
    pub fn new(gpu: GpuContext) -> GpuKernels {
        GpuKernels::with_options(gpu, &GpuOptions::default())
    }

    /// Kernels on `gpu`. The proximity passes run there on a hardware GPU; on a software
    /// adapter (lavapipe) they stay on the CPU unless `options` say otherwise: the kernel's
    /// broad phase walks every cell within reach of each moving vertex (reach set by the
    /// longest edge), which lavapipe runs hundreds of times slower than the CPU's per-step face
    /// grid. Runs ahead likewise.
    pub fn with_options(gpu: GpuContext, options: &GpuOptions) -> GpuKernels {
        let hardware = !gpu.adapter.software;
        GpuKernels {
            last_selection: 0,
            proximity_on_gpu: options.proximity_on_gpu.unwrap_or(hardware),
            backstop_on_gpu: options.backstop_filter_on_gpu,
            clamp_ahead: options.clamp_in_one_submission,
            run_ahead: options.runs_ahead.unwrap_or(hardware),
            step: StepBuffers::new(&gpu),
            readback: ReusableBuffer::readback("step readback"),
            gpu,
            resident: None,
            failed: None,
            fail_after: None,
            uploads: Uploads::default(),
            filter: BackstopFilter::default(),
            ahead: None,
            last_move: 0.0,
            step_limit: None,
            opened: None,
            no_run_at: None,
            steps_taken: Vec::new(),
            plan: Vec::new(),
            plan_first: 0,
            plan_next: 0,
            run_length: 0,
            run_taken: 0,
            queued: run_ahead::Queue::new(),
            taken: None,
            taken_filed: false,
            check_filing: false,
            filing_error: None,
            check_read_backs: 0,
        }
    }

    /// The adapter the kernels run on.
    pub fn adapter(&self) -> &super::AdapterSummary {
        &self.gpu.adapter
    }

    /// Runs the proximity passes on the GPU (`true`) or on the CPU.
    pub fn set_proximity_on_gpu(&mut self, on: bool) {
        self.proximity_on_gpu = on;
    }

    pub fn proximity_on_gpu(&self) -> bool {
        self.proximity_on_gpu
    }

    /// With the proximity passes on the GPU, runs the samples given in one call ahead in one
    /// submission (`true`) or one submission per step ([`GpuOptions::runs_ahead`]).
    pub fn set_run_ahead(&mut self, on: bool) {
        self.run_ahead = on;
    }

    /// Before the host refiles over what the GPU filed while samples ran ahead, reads that
    /// filing back and checks it against the mesh (`Hashed::check`); the first fault is
    /// reported by `check_copy`. A validator for tests: it reads the whole filing back.
    pub fn set_check_filing(&mut self, on: bool) {
        self.check_filing = on;
    }

    /// See [`GpuKernels::set_check_filing`]: called before anything may refile.
    fn check_gpu_filing(&mut self, mesh: &Mesh) {
        let Some(h) = self.resident.as_ref().and_then(|r| r.hashed.as_ref()) else {
            return;
        };
        if self.check_filing && h.filed_on_gpu && self.filing_error.is_none() {
            let before = self.gpu.read_backs();
            self.filing_error = h.check(&self.gpu, mesh).err();
            self.check_read_backs += self.gpu.read_backs() - before;
        }
    }

    /// Makes the GPU calls after the next `calls` fail, as a lost device would: for tests of
    /// the fallback.
    pub fn fail_after(&mut self, calls: usize) {
        self.fail_after = Some(calls);
    }

    fn check_injected_failure(&mut self) -> Result<(), GpuError> {
        match &mut self.fail_after {
            Some(0) => Err(GpuError::Readback("device lost (simulated)".into())),
            Some(n) => {
                *n -= 1;
                Ok(())
            }
            None => Ok(()),
        }
    }

    /// Brings the GPU copy up to date with `mesh` and makes its hash table, of `cell` sized
    /// cells, fresh enough for `table_use` (rebuilt when missing or drifted too far). A free
    /// function of the fields it needs, so that callers keep the step buffers borrowed beside
    /// what it returns.
    fn prepare<'a>(
        gpu: &GpuContext,
        (resident, uploads): (&'a mut Option<Resident>, &mut Uploads),
        mesh: &Mesh,
        cell: f32,
        table_use: TableUse,
    ) -> Result<&'a mut Resident, GpuError> {
        let r = GpuKernels::sync(gpu, (resident, uploads), mesh)?;
        let stale = table_use.drift_limit(cell).is_some_and(|limit| {
            r.hashed.as_ref().is_none_or(|h| {
                h.drift > limit || h.filed_on_gpu || h.table.inv_cell_size != 1.0 / cell
            })
        });
        // Drift is undone by filing the moved vertices in the overlay; the table is rebuilt
        // over every vertex only when there is none yet, its cells changed size, or the
        // overlay grew too large.
        let refiled = stale
            && r.hashed
                .as_mut()
                .is_some_and(|h| h.table.inv_cell_size == 1.0 / cell && h.refile(gpu, mesh, &[]));
        if refiled {
            uploads.overlay_filings += 1;
        }
        if stale && !refiled {
            let count = r.vertices.count;
            // Rows for every vertex there is room for: the overlay files new ones here.
            let positions = gpu.output_buffer::<Vec3>("hashed positions", r.capacity);
            let mut encoder = gpu.encoder("hash table");
            uploads.table_builds += 1;
            encoder.copy_buffer_to_buffer(
                &r.vertices.positions,
                0,
                &positions,
                0,
                (count * std::mem::size_of::<Vec3>()) as u64,
            );
            let table = GpuHashTable::record(
                gpu,
                &mut encoder,
                &positions,
                &r.vertices.flags,
                count,
                1.0 / cell,
                table_size_for(count),
            )?;
            gpu.submit(encoder);
            r.hashed = Some(Hashed {
                table,
                positions,
                marks: gpu.output_buffer::<u32>("overlay marks", r.capacity),
                drift: 0.0,
                overlay: None,
                moved: Vec::new(),
                filed_on_gpu: false,
                gpu_drift: None,
            });
        }
        Ok(r)
    }

    /// Brings the GPU copy up to date with `mesh`.
    fn sync<'a>(
        gpu: &GpuContext,
        (resident, uploads): (&'a mut Option<Resident>, &mut Uploads),
        mesh: &Mesh,
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
        if r.version.flags != version.flags {
            gpu.queue
                .write_buffer(&r.vertices.flags, 0, bytemuck::cast_slice(flag_bits(mesh)));
        }
        r.version = version;
        Ok(r)
    }

    fn gpu_deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        selection: &[(u32, f32)],
    ) -> Result<Vec<Vec3>, GpuError> {
        if selection.is_empty() {
            return Ok(Vec::new());
        }
        self.check_injected_failure()?;
        self.drop_all_ahead(mesh);
        let (gpu, step, readback) = (&self.gpu, &mut self.step, &mut self.readback);
        let r = GpuKernels::prepare(
            gpu,
            (&mut self.resident, &mut self.uploads),
            mesh,
            cell_size(state),
            TableUse::None,
        )?;
        let entries: Vec<SelectedVertex> = selection
            .iter()
            .map(|&(vertex, weight)| SelectedVertex { vertex, weight })
            .collect();
        step.selected.upload(gpu, &entries)?;
        gpu.queue.write_buffer(
            &step.selection_count,
            0,
            bytemuck::bytes_of(&(entries.len() as u32)),
        );
        let bytes = (entries.len() * std::mem::size_of::<Vec3>()) as u64;
        step.targets.reserve(gpu, bytes)?;
        let mut encoder = gpu.encoder("deform");
        record_deform(
            gpu,
            &mut encoder,
            &DeformBuffers {
                selection: SelectionBuffers {
                    positions: &r.vertices.positions,
                    normals: &r.normals,
                    selected: step.selected.buffer(),
                    selection_count: &step.selection_count,
                },
                neighbour_rows: &r.neighbour_table,
                neighbours: &r.neighbours,
                frame_sums: &step.frame_sums,
            },
            &deform_params(dab, entries.len()),
            step.targets.buffer(),
        )?;
        let data = readback.read_back_parts(gpu, encoder, &[(step.targets.buffer(), bytes)])?;
        Ok(bytemuck::pod_collect_to_vec(&data))
    }

    /// Selection, brush frame and deformation in one submission: the selection kernel fills
    /// the resident list; at a sample's start `brush_frame` sums it (dispatched from the
    /// count) and `deform` takes the frame from the sums; `deform` moves the first `guess`
    /// entries. The count, that head of the list, the sums and the targets come back in one
    /// map (`GpuSelection::submit_and_read`). A selection longer than the guess reads the rest
    /// of the list and deforms it apart.
    ///
    /// With `clamp_within` (a step limit), the same submission goes on through the step's
    /// proximity passes and filter: `moving_entries` builds the moving list and the rings from
    /// the selection list, and the passes run over the guessed slots, sized as if no vertex
    /// moved farther than [`AHEAD_MOVE_GROWTH`] times the last step's longest move, within the
    /// limit. The result is kept for the pipeline's `clamp` ([`ClampedAhead`]) when that held
    /// (so the step is one step) and the selection and rings fitted their room; otherwise the
    /// positions the passes wrote are put back.
    fn gpu_select_and_deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        (source, deforms): (FrameSource, bool),
        clamp_within: Option<f32>,
    ) -> Result<Deformed, GpuError> {
        self.check_injected_failure()?;
        self.check_gpu_filing(mesh);
        self.drop_all_ahead(mesh);
        let filter = self.backstop_on_gpu;
        // The passes' reach, and their work with its cube, grows with the move they assume:
        // twice the last step's longest move (within the limit), which consecutive steps of a
        // stroke rarely exceed.
        let assumed_move = clamp_within
            .filter(|_| deforms && self.proximity_on_gpu && self.clamp_ahead)
            .map(|limit| self.assumed_move(limit));
        let (gpu, step, readback) = (&self.gpu, &mut self.step, &mut self.readback);
        let r = GpuKernels::prepare(
            gpu,
            (&mut self.resident, &mut self.uploads),
            mesh,
            cell_size(state),
            match assumed_move {
                Some(_) => TableUse::Proximity,
                None => TableUse::Select {
                    radius: dab.brush.radius,
                },
            },
        )?;
        let capacity = r.selection.capacity;
        let guess = selection_guess(self.last_selection, capacity);
        // The rings of the guessed slots must fit one binding (`moving_entries` writes them).
        let assumed_move = assumed_move
            .filter(|_| ring_bytes(guess) <= gpu.limits.max_storage_buffer_binding_size);
        step.reserve_sample(
            gpu,
            (r, mesh),
            guess,
            deforms,
            assumed_move.is_some(),
            filter,
        )?;
        let r = &*r;
        let mut encoder = gpu.encoder("select and deform");
        let ahead = assumed_move.map(|assumed_move| AheadBounds {
            assumed_move,
            drift: r.hashed().drift,
        });
        if ahead.is_some() {
            step.start_gate(gpu, state.max_edge);
        }
        let recorded = record_sample(
            gpu,
            &mut encoder,
            (r, step),
            state,
            dab,
            (source, deforms),
            guess,
            ahead,
            filter,
        )?;
        let read = r
            .selection
            .submit_and_read(gpu, encoder, readback, guess, &recorded.parts)?;
        let list = read.list;
        let count = list.len();
        let whole_list = read.head == count;
        let layout = recorded.layout;
        let parts = layout.split(&read.extra, dab);
        self.last_selection = count;
        let (order, selection) = in_vertex_order(&list);
        let targets: Option<Vec<Vec3>> = (deforms && count > 0 && whole_list).then(|| {
            permuted(
                &order,
                &bytemuck::pod_collect_to_vec(&parts.targets[..count * 12]),
            )
        });
        let frame = parts.frame;
        let longest = targets
            .as_ref()
            .map(|targets| longest_move(mesh, &selection, targets));
        if let Some(longest) = longest {
            self.last_move = longest;
        }
        if let (Some(assumed), Some(clamp_read)) = (assumed_move, layout.clamp) {
            let vertices: Vec<u32> = selection.iter().map(|&(v, _)| v).collect();
            // Within the assumed move, which is within the step limit: one step, which moves
            // the selection to exactly these targets. The gate checked the same on the GPU.
            let stopped = parts.gate.is_some_and(|g| g.stopped != 0);
            let kept = targets.as_ref().filter(|_| {
                !stopped && parts.ring_overflows == Some(0) && longest.is_some_and(|l| l <= assumed)
            });
            match kept {
                Some(targets) => {
                    let (finals, backstop) = step.parse_clamp(parts.clamp, guess, clamp_read);
                    self.ahead = Some(ClampedAhead {
                        vertices,
                        targets: targets.clone(),
                        finals: permuted(&order, &finals),
                        backstop,
                    });
                }
                // Nothing selected: nothing moved, nothing to drop.
                None if vertices.is_empty() => {}
                // Stopped by the gate before they moved anything.
                None if stopped => self.uploads.gated_ahead += 1,
                // The passes moved what they were wrong about.
                None => put_back(gpu, Some(r), &mut self.uploads, mesh, &vertices),
            }
        }
        let targets = match (deforms && count > 0, targets) {
            (true, None) => {
                let dab = Dab { frame, ..*dab };
                Some(self.gpu_deform(state, mesh, &dab, &selection)?)
            }
            (_, targets) => targets,
        };
        Ok(Deformed {
            selection,
            frame,
            targets,
            deform_millis: 0.0,
        })
    }

    /// The proximity passes of one step on the GPU, as [`clamp_moves`] runs them, over entries
    /// and rings the host builds (`moving_vertices`); see [`record_clamp`]. Returns the final
    /// positions, and the filter's undecided pairs (or `Backstop::Gather` when it did not run
    /// or they overflowed its room). One submission, one read-back.
    fn gpu_clamp(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        selection: &[(u32, f32)],
        targets: &[Vec3],
        before: &[Vec3],
    ) -> Result<(Vec<Vec3>, Backstop), GpuError> {
        if selection.is_empty() {
            return Ok((Vec::new(), Backstop::Undecided(Vec::new())));
        }
        self.check_injected_failure()?;
        let filter = self.backstop_on_gpu;
        let (gpu, step, readback) = (&self.gpu, &mut self.step, &mut self.readback);
        let r = GpuKernels::prepare(
            gpu,
            (&mut self.resident, &mut self.uploads),
            mesh,
            cell_size(state),
            TableUse::Proximity,
        )?;
        r.ensure_topology(gpu, mesh)?;
        let vertices: Vec<u32> = selection.iter().map(|&(v, _)| v).collect();
        let (moving, rings) = moving_vertices(mesh, &vertices, before, state.ring);
        let count = moving.len();
        step.moving.upload(gpu, &moving)?;
        step.rings.upload(gpu, &rings)?;
        step.targets.upload(gpu, targets)?;
        let bounds = PassBounds {
            count,
            step_move: crate::geom::largest_move(before, targets),
            moved_edge: if filter {
                moved_edge_bound(mesh, &vertices, before, targets)
            } else {
                0.0
            },
            drift: r.hashed().drift,
            counted_by: None,
        };
        step.reserve_clamp(gpu, count, filter)?;
        let mut encoder = gpu.encoder("clamp");
        let read = record_clamp(gpu, &mut encoder, (r, step), state, &bounds, filter)?;
        let mut parts = vec![(step.finals.buffer(), read.finals_bytes)];
        if let Some(pair_bytes) = read.pair_bytes {
            parts.push((&step.pair_count, 4));
            parts.push((step.pairs.buffer(), pair_bytes));
        }
        let data = readback.read_back_parts(gpu, encoder, &parts)?;
        let (finals, backstop) = step.parse_clamp(&data, count, read);
        tally(&mut self.filter, &backstop, filter);
        Ok((finals, backstop))
    }

    /// [`StepKernels::select_deform_and_clamp`] on the GPU, falling back to the CPU: the call a
    /// run queued, else at the start of a given sample a run of the given samples from it,
    /// else one submission for this step.
    fn select_deform_and_clamp_on_gpu(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        (source, at): (FrameSource, CallAt),
        step_limit: f32,
    ) -> Deformed {
        let how = (source, true);
        self.taken_filed = false;
        let taken = match at {
            CallAt::Start { sample } => {
                let planned = self.plan_index(sample);
                self.take_queued_start(mesh, planned, state.max_edge)
                    .or_else(|| {
                        let from = planned.filter(|&at| self.may_start_run(at))?;
                        let run = (None, Some(from));
                        self.on_gpu(|k| k.gpu_run_ahead(state, mesh, run, step_limit))?;
                        self.take_queued_start(mesh, planned, state.max_edge)
                    })
            }
            CallAt::Step { .. } => self.take_queued_step(mesh, (at, None), state.max_edge),
        };
        if let Some(deformed) = taken {
            return deformed;
        }
        self.on_gpu(|k| k.gpu_select_and_deform(state, mesh, dab, how, Some(step_limit)))
            .unwrap_or_else(|| CpuKernels.select_and_deform(state, mesh, dab, how))
    }

    /// The longest move passes recorded before the moves are known are sized for: twice the
    /// last step's longest move, within the step `limit` (the limit before the first).
    fn assumed_move(&self, limit: f32) -> f32 {
        match self.last_move {
            0.0 => limit,
            last => (AHEAD_MOVE_GROWTH * last).min(limit),
        }
    }

    /// Drops the passes a merged submission ran ahead when the pipeline did not take them:
    /// the GPU's positions of those vertices go back to the mesh's. Samples queued after them
    /// were recorded on their moves, and go too.
    fn drop_ahead(&mut self, mesh: &Mesh) {
        if let Some(ahead) = self.ahead.take() {
            self.drop_queued(mesh);
            let resident = self.resident.as_ref();
            put_back(
                &self.gpu,
                resident,
                &mut self.uploads,
                mesh,
                &ahead.vertices,
            );
        }
    }

    /// Drops whatever ran ahead — the passes of one step and the samples queued — when the
    /// pipeline asks for something else.
    fn drop_all_ahead(&mut self, mesh: &Mesh) {
        self.drop_ahead(mesh);
        self.drop_queued(mesh);
    }

    /// Sends the rows the pipeline changed, and notes how far they may have drifted.
    fn gpu_moved(&mut self, mesh: &Mesh, vertices: &[u32], max_move: f32) {
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
    fn gpu_remeshed(&mut self, mesh: &Mesh, since: MeshVersion, changed: &[u32]) {
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

    fn gpu_normals_changed(&mut self, mesh: &Mesh, vertices: &[u32]) {
        if let Some(r) = self.resident.as_ref() {
            upload_rows(&self.gpu, &r.normals, mesh.normals(), vertices);
        }
    }

    /// `run`'s result, unless the GPU was given up before or fails now (then given up for
    /// good): the caller falls back to the CPU on `None`.
    fn on_gpu<T>(&mut self, run: impl FnOnce(&mut GpuKernels) -> Result<T, GpuError>) -> Option<T> {
        if self.failed.is_some() {
            return None;
        }
        run(self).map_err(|error| self.give_up(error)).ok()
    }

    /// Gives the GPU up for good, keeping why (the pipeline reports it).
    fn give_up(&mut self, error: GpuError) {
        self.failed = Some(error.to_string());
        self.resident = None;
    }
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

/// How a step's proximity passes are sized: `count` slots of the step's moving list, no move
/// longer than `step_move`, no edge after the step longer than `moved_edge` (read by the
/// filter only); when `counted_by` holds the selection count the slots were built from
/// (`moving_entries`), the first pass is sized from it by the GPU, vacant slots left out.
struct PassBounds<'a> {
    count: usize,
    step_move: f32,
    moved_edge: f32,
    /// How far any vertex may be from where the table filed it.
    drift: f32,
    counted_by: Option<&'a wgpu::Buffer>,
}

/// What a recorded clamp leaves to read back after it: the finals, and with the filter its
/// pair count and pairs.
#[derive(Debug, Clone, Copy)]
struct ClampRead {
    finals_bytes: u64,
    pair_bytes: Option<u64>,
}

impl StepBuffers {
    /// Starts the gate for a single step's passes or a run's: no stop yet, and the edge bound
    /// at `max_edge` (the pipeline's). Written before the submission's commands run.
    fn start_gate(&self, gpu: &GpuContext, max_edge: f32) {
        gpu.queue.write_buffer(
            &self.gate_status,
            0,
            bytemuck::bytes_of(&GateStatus::starting(max_edge)),
        );
    }

    /// Room for [`record_sample`] over `guess` slots (with `ahead`, its passes too: the
    /// topology made resident).
    fn reserve_sample(
        &mut self,
        gpu: &GpuContext,
        (r, mesh): (&mut Resident, &Mesh),
        guess: usize,
        deforms: bool,
        ahead: bool,
        filter: bool,
    ) -> Result<(), GpuError> {
        if deforms {
            self.targets
                .reserve(gpu, (guess * std::mem::size_of::<Vec3>()) as u64)?;
        }
        if ahead {
            r.ensure_topology(gpu, mesh)?;
            self.moving
                .reserve(gpu, (guess * std::mem::size_of::<MovingVertex>()) as u64)?;
            self.ring_slots.reserve(gpu, ring_bytes(guess))?;
            self.reserve_clamp(gpu, guess, filter)?;
        }
        Ok(())
    }

    /// Room for a clamp over `count` slots (`record_clamp`), before its buffers are borrowed.
    fn reserve_clamp(
        &mut self,
        gpu: &GpuContext,
        count: usize,
        filter: bool,
    ) -> Result<(), GpuError> {
        self.pulls
            .reserve(gpu, (count * std::mem::size_of::<u32>()) as u64)?;
        self.finals
            .reserve(gpu, (count * std::mem::size_of::<Vec3>()) as u64)?;
        if filter {
            let pair_bytes = (self.pair_capacity * std::mem::size_of::<[u32; 2]>()) as u64;
            self.pairs.reserve(gpu, pair_bytes)?;
        }
        Ok(())
    }

    /// The finals of a clamp over `count` slots and what it leaves the backstop, from the
    /// bytes read back (finals first, then the filter's count and pairs). An overflow of the
    /// pairs' room grows it for the next step.
    fn parse_clamp(&mut self, data: &[u8], count: usize, read: ClampRead) -> (Vec<Vec3>, Backstop) {
        let at = read.finals_bytes as usize;
        let finals = bytemuck::pod_collect_to_vec(&data[..count * std::mem::size_of::<Vec3>()]);
        let Some(pair_bytes) = read.pair_bytes else {
            return (finals, Backstop::Gather);
        };
        let found =
            u32::from_le_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]]) as usize;
        // The room the recording had (a later recording may have more).
        let room = pair_bytes as usize / std::mem::size_of::<[u32; 2]>();
        if found > room {
            // Room for them next time; this step's backstop searches on the CPU.
            self.pair_capacity = self.pair_capacity.max(found.next_power_of_two());
            return (finals, Backstop::Gather);
        }
        let pairs = bytemuck::pod_collect_to_vec(&data[at + 4..at + 4 + 8 * found]);
        (finals, Backstop::Undecided(pairs))
    }
}

/// The head of the selection list read back with its count: twice the `last` selection,
/// within the list's `capacity`.
fn selection_guess(last: usize, capacity: usize) -> usize {
    (2 * last).max(SELECTION_GUESS).min(capacity)
}

/// Puts the GPU's rows of `vertices` back to the mesh's where passes run ahead wrote them and
/// the pipeline did not take them (counted as dropped).
fn put_back(
    gpu: &GpuContext,
    resident: Option<&Resident>,
    uploads: &mut Uploads,
    mesh: &Mesh,
    vertices: &[u32],
) {
    uploads.dropped_ahead += 1;
    run_ahead::put_back_rows(gpu, resident, mesh, vertices);
}

/// Counts what the filter left the CPU (`filter`: it ran).
fn tally(stats: &mut BackstopFilter, backstop: &Backstop, filter: bool) {
    match backstop {
        Backstop::Undecided(pairs) => {
            stats.filtered += 1;
            stats.undecided_pairs += pairs.len();
        }
        _ if filter => stats.overflowed += 1,
        _ => {}
    }
}

/// Records the proximity passes of one step, as [`clamp_moves`] runs them, over the slots of
/// `step.moving` (their rings in `step.ring_slots` when the GPU built them, else in
/// `step.rings`) and targets in `step.targets`: targets placed, a first pass against every
/// face, then passes against the faces pulled-back vertices moved until one pulls nothing (the
/// GPU sizes each pass from the last), the last sending what still collides back to its
/// start; final positions gathered; then, with `filter`, the backstop filter
/// (`wgsl/backstop.wgsl`) over the faces that moved. Buffers reserved beforehand
/// (`StepBuffers::reserve_clamp`); the topology resident.
fn record_clamp(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (r, step): (&Resident, &StepBuffers),
    state: &StrokeState<'_>,
    bounds: &PassBounds<'_>,
    filter: bool,
) -> Result<ClampRead, GpuError> {
    let hashed = r.hashed();
    let Some(ResidentTopology {
        buffer: topology,
        layout,
    }) = &r.topology
    else {
        unreachable!("the caller made the topology resident");
    };
    let count = bounds.count;
    let first = pass_params(
        (
            state.collision_distance,
            state.max_edge,
            bounds.drift + bounds.step_move,
        ),
        hashed.table.inv_cell_size,
        hashed.table.table_size,
        count,
        layout.vertex_rows_base,
    );
    // Vertices moved or changed since the main table was built are filed in the overlay:
    // each invocation walks its cell there too, and leaves them out of the main table.
    let overlay = hashed.overlay();
    let params = |all_faces: bool| ProximityParams {
        all_faces: all_faces as u32,
        overlay: overlay.is_some() as u32,
        overlay_mask: overlay.map_or(0, |o| o.table.table_size - 1),
        ..first
    };
    check_invocations(&params(true))?;
    let invocations = count * first.cells_per_entry as usize;
    let rings = match bounds.counted_by {
        Some(_) => step.ring_slots.buffer(),
        None => step.rings.buffer(),
    };
    // Without an overlay its bindings are never read: the main table's stand in.
    let proximity = ProximityBuffers {
        positions: &r.vertices.positions,
        offsets: &hashed.table.offsets,
        entries: &hashed.table.entries,
        topology,
        moving: step.moving.buffer(),
        rings,
        marks: &r.marks,
        overlay_marks: &hashed.marks,
        overlay_offsets: overlay.map_or(&hashed.table.offsets, |o| o.table.offsets),
        overlay_entries: overlay.map_or(&hashed.table.entries, |o| o.table.entries),
    };
    let apply = ApplyMovesBuffers {
        moving: step.moving.buffer(),
        targets: step.targets.buffer(),
        pulls: step.pulls.buffer(),
        positions: &r.vertices.positions,
        marks: &r.marks,
        next_count: &step.next_count,
        finals: step.finals.buffer(),
    };
    let pulls = step.pulls.buffer();
    let apply_params = |mode| ApplyParams {
        next_invocations: invocations as u32,
        ..ApplyParams::new(count, mode)
    };
    record_apply_moves(
        gpu,
        encoder,
        &apply,
        &ApplyParams::new(count, ApplyMode::Place),
        None,
    )?;
    for pass in 0..MAX_PASSES {
        // The first pass is sized by the host, or from the selection count; later ones by the
        // pass before, so that they shrink to nothing once a pass pulls nothing back.
        let (sized, apply_sized) = match (pass, bounds.counted_by) {
            (0, None) => (None, None),
            (0, Some(selection_count)) => {
                record_dispatch_args(
                    gpu,
                    encoder,
                    selection_count,
                    (count, first.cells_per_entry),
                    PROXIMITY_WORKGROUP_SIZE,
                    &step.pass_args,
                )?;
                (Some(&step.pass_args), None)
            }
            _ => (Some(&step.pass_args), Some(&step.apply_args)),
        };
        record_proximity(gpu, encoder, &proximity, &params(pass == 0), pulls, sized)?;
        encoder.clear_buffer(&step.next_count, 0, None);
        let mode = if pass + 1 == MAX_PASSES {
            ApplyMode::PullLast
        } else {
            ApplyMode::Pull
        };
        record_apply_moves(gpu, encoder, &apply, &apply_params(mode), apply_sized)?;
        // Both sizes from the one count: all invocations, or none after a quiet pass.
        record_dispatch_args(
            gpu,
            encoder,
            &step.next_count,
            (invocations, 1),
            PROXIMITY_WORKGROUP_SIZE,
            &step.pass_args,
        )?;
        record_dispatch_args(
            gpu,
            encoder,
            &step.next_count,
            (count, 1),
            APPLY_WORKGROUP_SIZE,
            &step.apply_args,
        )?;
    }
    record_apply_moves(
        gpu,
        encoder,
        &apply,
        &ApplyParams::new(count, ApplyMode::Gather),
        None,
    )?;
    let finals_bytes = (count * std::mem::size_of::<Vec3>()) as u64;
    if !filter {
        return Ok(ClampRead {
            finals_bytes,
            pair_bytes: None,
        });
    }
    let capacity = step.pair_capacity;
    let params = BackstopParams {
        overlay: overlay.is_some() as u32,
        overlay_mask: overlay.map_or(0, |o| o.table.table_size - 1),
        ..backstop_params(
            (state.max_edge, bounds.moved_edge),
            (bounds.drift, bounds.step_move),
            (hashed.table.inv_cell_size, hashed.table.table_size),
            count,
            layout.vertex_rows_base,
            capacity,
        )
    };
    // The map from vertex to moved entry lives in the marks for the filter's while.
    record_apply_moves(
        gpu,
        encoder,
        &apply,
        &ApplyParams::new(count, ApplyMode::MarkMoved),
        None,
    )?;
    encoder.clear_buffer(&step.pair_count, 0, None);
    record_backstop(
        gpu,
        encoder,
        &BackstopBuffers {
            positions: &r.vertices.positions,
            offsets: &hashed.table.offsets,
            entries: &hashed.table.entries,
            topology,
            moving: step.moving.buffer(),
            moved: &r.marks,
            overlay_marks: &hashed.marks,
            overlay_offsets: proximity.overlay_offsets,
            overlay_entries: proximity.overlay_entries,
        },
        &params,
        (step.pairs.buffer(), &step.pair_count),
    )?;
    record_apply_moves(
        gpu,
        encoder,
        &apply,
        &ApplyParams::new(count, ApplyMode::Clear),
        None,
    )?;
    Ok(ClampRead {
        finals_bytes,
        pair_bytes: Some((capacity * std::mem::size_of::<[u32; 2]>()) as u64),
    })
}

/// How a sample's passes, recorded before its moves are known, are sized: for moves up to
/// `assumed_move`, over a table whose vertices may have drifted `drift` from where they were
/// filed. Such passes go through the gate (`sample_gate`, started by
/// [`StepBuffers::start_gate`]): where those assumptions fail they move nothing.
#[derive(Debug, Clone, Copy)]
struct AheadBounds {
    assumed_move: f32,
    drift: f32,
}

/// What [`record_sample`] leaves to read back after the selection's count and list: `parts`,
/// in order, and how to split them.
struct RecordedSample<'b> {
    parts: Vec<(&'b wgpu::Buffer, u64)>,
    layout: SampleLayout,
}

/// How a recorded sample's parts split.
#[derive(Debug, Clone, Copy)]
struct SampleLayout {
    /// The sample's own normal when the frame is summed from the selection.
    frame_from_selection: Option<Option<Vec3>>,
    target_bytes: u64,
    /// Where the passes ran (through the gate, whose status follows the ring overflows).
    clamp: Option<ClampRead>,
}

/// A recorded sample's bytes after the selection list, split.
struct SampleBytes<'d> {
    frame: DabFrame,
    /// `target_bytes` of targets, in the list's order (empty for a brush that does not move).
    targets: &'d [u8],
    /// Rings `moving_entries` cut short, where the passes ran.
    ring_overflows: Option<u32>,
    /// The gate's verdict, where the passes went through it: when it stopped them they moved
    /// nothing.
    gate: Option<GateStatus>,
    /// The rest: what `StepBuffers::parse_clamp` reads.
    clamp: &'d [u8],
}

impl SampleLayout {
    fn split<'d>(&self, mut rest: &'d [u8], dab: &Dab) -> SampleBytes<'d> {
        let mut take = |bytes: u64| {
            let (part, after) = rest.split_at(bytes as usize);
            rest = after;
            part
        };
        let frame = match self.frame_from_selection {
            Some(normal) => {
                let sums = take((FRAME_SUM_WORDS * 4) as u64);
                frame_of_sums(&bytemuck::pod_read_unaligned(sums), dab, normal)
            }
            None => dab.frame,
        };
        let targets = take(self.target_bytes);
        let ring_overflows = self
            .clamp
            .map(|_| u32::from_le_bytes(take(4).try_into().expect("four bytes")));
        let gate = self
            .clamp
            .map(|_| bytemuck::pod_read_unaligned(take(std::mem::size_of::<GateStatus>() as u64)));
        SampleBytes {
            frame,
            targets,
            ring_overflows,
            gate,
            clamp: rest,
        }
    }
}

/// Records one sample's step into `encoder`: selection under `dab` (into the resident list),
/// at a sample's start the brush frame summed from it, with `deforms` the deformation of the
/// first `guess` entries, and with `ahead` `moving_entries` and the step's proximity passes
/// and filter over those slots. `state.max_edge` bounds the edges at the step's start. The
/// buffers are reserved beforehand.
#[allow(clippy::too_many_arguments)]
fn record_sample<'b>(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (r, step): (&'b Resident, &'b StepBuffers),
    state: &StrokeState<'_>,
    dab: &Dab,
    (source, deforms): (FrameSource, bool),
    guess: usize,
    ahead: Option<AheadBounds>,
    filter: bool,
) -> Result<RecordedSample<'b>, GpuError> {
    let drift = ahead.map_or(r.hashed().drift, |a| a.drift);
    record_brush_selection(gpu, encoder, r, state.active, dab, drift)?;
    let capacity = r.selection.capacity;
    let gate = || step.gate(r);
    if ahead.is_some() {
        record_gate_open(gpu, encoder, &gate())?;
    }
    let inputs = SelectionBuffers {
        positions: &r.vertices.positions,
        normals: &r.normals,
        selected: &r.selection.selected,
        selection_count: &r.selection.count,
    };
    let mut params = deform_params(dab, guess);
    let mut parts = Vec::new();
    let frame_from_selection = match source {
        FrameSource::Selection { normal } => {
            params.frame = frame_flags(normal);
            params.normal = normal.unwrap_or(Vec3::Z).to_array();
            record_dispatch_args(
                gpu,
                encoder,
                &r.selection.count,
                (capacity, 1),
                FRAME_WORKGROUP_SIZE,
                &step.frame_args,
            )?;
            record_brush_frame(
                gpu,
                encoder,
                &inputs,
                &frame_params(dab.frame.center, dab.brush.radius, capacity),
                &step.frame_sums,
                Workgroups::Indirect(&step.frame_args),
            )?;
            parts.push((&step.frame_sums, (FRAME_SUM_WORDS * 4) as u64));
            Some(normal)
        }
        FrameSource::Dab => None,
    };
    let target_bytes = if deforms {
        (guess * std::mem::size_of::<Vec3>()) as u64
    } else {
        0
    };
    if deforms {
        record_deform(
            gpu,
            encoder,
            &DeformBuffers {
                selection: inputs,
                neighbour_rows: &r.neighbour_table,
                neighbours: &r.neighbours,
                frame_sums: &step.frame_sums,
            },
            &params,
            step.targets.buffer(),
        )?;
        parts.push((step.targets.buffer(), target_bytes));
    }
    let mut clamp = None;
    if let Some(AheadBounds {
        assumed_move,
        drift,
        ..
    }) = ahead
    {
        let Some(topology) = &r.topology else {
            unreachable!("the caller made the topology resident");
        };
        encoder.clear_buffer(&step.ring_overflows, 0, None);
        record_moving_entries(
            gpu,
            encoder,
            &EntryBuffers {
                positions: &r.vertices.positions,
                layers: &r.vertices.layers,
                selected: &r.selection.selected,
                selection_count: &r.selection.count,
                topology: &topology.buffer,
            },
            &entry_params(guess, state.ring, topology.layout.vertex_rows_base),
            &BuiltEntryBuffers {
                moving: step.moving.buffer(),
                rings: step.ring_slots.buffer(),
                overflows: &step.ring_overflows,
            },
        )?;
        record_gate_check(gpu, encoder, &gate(), (guess, assumed_move, state.max_edge))?;
        // No vertex moves farther than assumed, so no edge grows by more than twice that.
        let bounds = PassBounds {
            count: guess,
            step_move: assumed_move,
            moved_edge: state.max_edge + 2.0 * assumed_move,
            drift,
            counted_by: Some(&r.selection.count),
        };
        let read = record_clamp(gpu, encoder, (r, step), state, &bounds, filter)?;
        parts.push((&step.ring_overflows, 4));
        parts.push((&step.gate_status, std::mem::size_of::<GateStatus>() as u64));
        parts.push((step.finals.buffer(), read.finals_bytes));
        if let Some(pair_bytes) = read.pair_bytes {
            parts.push((&step.pair_count, 4));
            parts.push((step.pairs.buffer(), pair_bytes));
        }
        clamp = Some(read);
    }
    Ok(RecordedSample {
        parts,
        layout: SampleLayout {
            frame_from_selection,
            target_bytes,
            clamp,
        },
    })
}

/// The order that sorts a selection list by vertex, and the list so sorted: the kernels append
/// in whatever order their threads ran; the pipeline works in vertex order (its sums and the
/// CPU's agree then).
fn in_vertex_order(list: &[SelectedVertex]) -> (Vec<usize>, Vec<(u32, f32)>) {
    let mut order: Vec<usize> = (0..list.len()).collect();
    order.sort_unstable_by_key(|&i| list[i].vertex);
    let selection = order
        .iter()
        .map(|&i| (list[i].vertex, list[i].weight))
        .collect();
    (order, selection)
}

/// `values` (one per list entry) permuted as [`in_vertex_order`] sorted the list.
fn permuted<T: Copy>(order: &[usize], values: &[T]) -> Vec<T> {
    order.iter().map(|&i| values[i]).collect()
}

/// Records a selection under `dab` into the resident selection buffers.
fn record_brush_selection(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    r: &Resident,
    active: &[bool],
    dab: &Dab,
    drift: f32,
) -> Result<(), GpuError> {
    let hashed = r.hashed();
    let active_words: Vec<u32> = active.iter().map(|&a| a as u32).collect();
    let active_buffer = gpu.storage_buffer("active layers", &active_words, false);
    record_select(
        gpu,
        encoder,
        &r.vertices,
        &active_buffer,
        active.len(),
        &HashedVertices {
            table: &hashed.table,
            positions: &hashed.positions,
            drift,
            overlay: hashed.overlay(),
        },
        &BrushSphere {
            center: dab.frame.center,
            radius: dab.brush.radius,
            falloff: dab.brush.falloff,
        },
        &r.selection,
    )
}

/// The cell size the pipeline's grid uses (the table is built with the same).
fn cell_size(state: &StrokeState<'_>) -> f32 {
    state.grid.map_or(state.max_edge, |g| g.cell_size())
}

/// The vertex flags as the kernels read them, one `u32` each.
fn flag_bits(mesh: &Mesh) -> &[u32] {
    bytemuck::cast_slice(mesh.flags())
}

impl StepKernels for GpuKernels {
    fn name(&self) -> String {
        self.gpu.adapter.name.clone()
    }

    fn collides_on_gpu(&self) -> bool {
        self.proximity_on_gpu && self.failed.is_none()
    }

    fn failure(&self) -> Option<String> {
        self.failed.clone()
    }

    fn warm_up(&mut self, mesh: &Mesh, cell_size: f32) {
        // Not counted as a GPU call by the `fail_after` hook: the tests of the fallback aim
        // their failures at the strokes' calls.
        self.on_gpu(|k| {
            let tables = (&mut k.resident, &mut k.uploads);
            GpuKernels::prepare(&k.gpu, tables, mesh, cell_size, TableUse::Present)?;
            // Done here, not in the first call that reads something back.
            k.gpu.wait()
        });
    }

    fn select(&mut self, state: &StrokeState<'_>, mesh: &Mesh, dab: &Dab) -> Vec<(u32, f32)> {
        // The selection alone: the same submission as with a deformation, less its passes.
        let alone = (FrameSource::Dab, false);
        self.on_gpu(|k| k.gpu_select_and_deform(state, mesh, dab, alone, None))
            .map(|selected| selected.selection)
            .unwrap_or_else(|| CpuKernels.select(state, mesh, dab))
    }

    fn select_and_deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        how: (FrameSource, bool),
    ) -> Deformed {
        self.on_gpu(|k| k.gpu_select_and_deform(state, mesh, dab, how, None))
            .unwrap_or_else(|| CpuKernels.select_and_deform(state, mesh, dab, how))
    }

    fn select_deform_and_clamp(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        (source, at): (FrameSource, CallAt),
        step_limit: f32,
    ) -> Deformed {
        let deformed =
            self.select_deform_and_clamp_on_gpu(state, mesh, dab, (source, at), step_limit);
        self.step_limit = Some(step_limit);
        if let CallAt::Start { sample } = at {
            self.steps_taken.clear();
            self.opened = Some(OpenedSample {
                sample,
                planned: self.plan_index(sample),
            });
        }
        deformed
    }

    fn given(&mut self, mesh: &Mesh, first: usize, probes: &[SampleProbe]) {
        self.drop_queued(mesh);
        self.plan = probes.to_vec();
        self.plan_first = first;
        self.plan_next = 0;
        self.opened = None;
        self.no_run_at = None;
        self.steps_taken.clear();
    }

    fn deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        selection: &[(u32, f32)],
        at: Option<CallAt>,
    ) -> Vec<Vec3> {
        // The first step of a sample of several: the selection its start found, under the same
        // brush (a share of the move). Its steps and the samples after it run ahead in one
        // submission; or, when they do not, the step is selected again with the deformation
        // and its passes in one submission, as a later step is, when the selection comes out
        // the same.
        let opened = self.opened.take();
        let first_step = match (opened, at) {
            (
                Some(o),
                Some(CallAt::Step {
                    sample,
                    k: 0,
                    steps,
                }),
            ) if o.sample == sample => Some((o, steps)),
            _ => None,
        };
        if let (Some((opened, steps)), Some(limit)) = (first_step, self.step_limit)
            && self.failed.is_none()
        {
            let sample = (opened.sample, steps);
            if let Some(targets) = self.run_steps_ahead(
                state,
                mesh,
                (dab, selection),
                (sample, opened.planned),
                limit,
            ) {
                return targets;
            }
            let how = (FrameSource::Dab, true);
            if let Some(Deformed {
                selection: found,
                targets: Some(targets),
                ..
            }) = self.on_gpu(|k| k.gpu_select_and_deform(state, mesh, dab, how, Some(limit)))
                && found == selection
            {
                return targets;
            }
        }
        self.on_gpu(|k| k.gpu_deform(state, mesh, dab, selection))
            .unwrap_or_else(|| CpuKernels.deform(state, mesh, dab, selection, at))
    }

    fn clamp(
        &mut self,
        state: &StrokeState<'_>,
        region: &mut Region,
        mesh: &mut Mesh,
        moves: StepMoves<'_>,
        before: &[Vec3],
    ) -> Backstop {
        let (selection, targets, _) = moves;
        let same = self.ahead.as_ref().is_some_and(|ahead| {
            ahead.targets.as_slice() == targets
                && selection
                    .iter()
                    .map(|&(v, _)| v)
                    .eq(ahead.vertices.iter().copied())
        });
        match self.ahead.take() {
            Some(ahead) if same => {
                self.uploads.clamped_ahead += 1;
                tally(&mut self.filter, &ahead.backstop, self.backstop_on_gpu);
                let positions = mesh.positions_mut();
                for (&v, &p) in ahead.vertices.iter().zip(&ahead.finals) {
                    positions[v as usize] = p;
                }
                self.taken = Some((ahead.vertices, ahead.finals));
                return ahead.backstop;
            }
            // Passes run ahead for other moves: dropped, with the samples queued after them.
            not_these => {
                self.ahead = not_these;
                self.drop_ahead(mesh);
            }
        }
        if self.proximity_on_gpu
            && let Some((finals, backstop)) =
                self.on_gpu(|k| k.gpu_clamp(state, mesh, selection, targets, before))
        {
            let positions = mesh.positions_mut();
            for (&(v, _), p) in selection.iter().zip(finals) {
                positions[v as usize] = p;
            }
            return backstop;
        }
        clamp_in_region(state, region, mesh, moves, before)
    }

    fn moved(&mut self, mesh: &Mesh, vertices: &[u32], max_move: f32) {
        self.drop_ahead(mesh);
        self.check_taken(mesh);
        if self.failed.is_none() {
            self.gpu_moved(mesh, vertices, max_move);
        }
    }

    fn normals_changed(&mut self, mesh: &Mesh, vertices: &[u32]) {
        if self.failed.is_none() {
            self.gpu_normals_changed(mesh, vertices);
        }
    }

    fn remeshed(&mut self, mesh: &Mesh, since: MeshVersion, changed: &[u32]) {
        self.drop_all_ahead(mesh);
        if self.failed.is_none() {
            self.gpu_remeshed(mesh, since, changed);
        }
    }

    fn uploads(&self) -> Option<Uploads> {
        Some(Uploads {
            submissions: self.gpu.submissions(),
            read_backs: self.gpu.read_backs() - self.check_read_backs,
            ..self.uploads
        })
    }

    fn backstop_filter(&self) -> Option<BackstopFilter> {
        (self.proximity_on_gpu && self.backstop_on_gpu).then_some(self.filter)
    }

    fn gpu_memory(&self, mesh: &Mesh) -> Option<GpuMemory> {
        self.resident.as_ref()?;
        let report = self.gpu.device.generate_allocator_report();
        Some(GpuMemory {
            allocated_bytes: report.as_ref().map(|r| r.total_allocated_bytes),
            reserved_bytes: report.as_ref().map(|r| r.total_reserved_bytes),
            budget_bytes: resident_bytes(mesh),
            budget_limit_bytes: self.gpu.budget_bytes,
        })
    }

    fn check_copy(&self, mesh: &Mesh) -> Result<(), String> {
        if let Some(error) = &self.filing_error {
            return Err(format!("the GPU's filing of samples run ahead: {error}"));
        }
        match &self.resident {
            Some(r) if r.version == mesh.version() => r.check(&self.gpu, mesh),
            Some(_) => Err("the GPU copy is behind the mesh".into()),
            None => Ok(()),
        }
    }
}
