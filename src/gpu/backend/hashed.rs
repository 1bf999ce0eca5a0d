//! The hash table the GPU's queries find vertices through, as the kernels keep it between
//! steps: built once; the vertices moved or changed since are filed in its overlay
//! (`crate::gpu::overlay`) and refiled when they drift farther than the use tolerates
//! ([`TableUse`]) — queries grow their reach by the drift until then (`select`, `proximity`);
//! rebuilt over every vertex only when the overlay passes its limit; between samples run
//! ahead, the GPU files each sample's moved vertices in the overlay itself, and the host
//! refiles after.

use glam::Vec3;

use crate::collide::StrokeState;
use crate::gpu::reusable::{Patches, ReusableBuffer};
use crate::gpu::{
    Filed, GpuContext, GpuError, GpuHashTable, OverlayBuffers, SlotBuffers, TableBuffers,
    VertexBuffers, overlay_limit, overlay_table, read_table, record_overlay_members,
    record_overlay_table, table_size_for,
};
use crate::grid::{cell_coordinates, hash_cell};
use crate::mesh::Mesh;
use crate::pipeline::Uploads;

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
pub(super) enum TableUse {
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
pub(super) struct Hashed {
    pub(super) table: GpuHashTable,
    /// Where each vertex was filed: at the build, or for the overlay's members at their filing.
    pub(super) positions: wgpu::Buffer,
    /// Per vertex: its slot in the overlay + 1 (`super::overlay`), 0 when not filed there.
    pub(super) marks: wgpu::Buffer,
    /// How far any vertex may have moved since it was filed.
    pub(super) drift: f32,
    /// The vertices moved or changed since the build, filed apart (`super::overlay`).
    pub(super) overlay: Option<Overlay>,
    /// Vertices moved since the last filing (unsorted, may repeat).
    pub(super) moved: Vec<u32>,
    /// The GPU refiled the overlay since the host did (samples run ahead): `overlay.members`
    /// and the marks no longer say what it holds, so the host refiles before the next use.
    pub(super) filed_on_gpu: bool,
    /// While the GPU's filing is in place and no sample run ahead was dropped since: how far
    /// any vertex may be from where it is filed — the drift the run's queries assumed, plus
    /// the moves taken since that the GPU did not file. `None` when unknown.
    pub(super) gpu_drift: Option<f32>,
}

/// The overlay table and its members.
pub(super) struct Overlay {
    /// Ascending vertex ids, as the host filed them; slot + 1 is each one's mark.
    pub(super) members: Vec<u32>,
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
    /// Makes the table in `slot`, of `cell` sized cells, fresh enough for `table_use`: the
    /// moved vertices refiled in the overlay, or the table built over the first
    /// `vertices.count` of `vertices` (rebuilt when missing or drifted too far), with rows for
    /// `capacity`.
    pub(super) fn refresh(
        slot: &mut Option<Hashed>,
        gpu: &GpuContext,
        uploads: &mut Uploads,
        mesh: &Mesh,
        (vertices, capacity): (&VertexBuffers, usize),
        cell: f32,
        table_use: TableUse,
    ) -> Result<(), GpuError> {
        let stale = table_use.drift_limit(cell).is_some_and(|limit| {
            slot.as_ref().is_none_or(|h| {
                h.drift > limit || h.filed_on_gpu || h.table.inv_cell_size != 1.0 / cell
            })
        });
        // Drift is undone by filing the moved vertices in the overlay; the table is rebuilt
        // over every vertex only when there is none yet, its cells changed size, or the
        // overlay grew too large.
        let refiled = stale
            && slot
                .as_mut()
                .is_some_and(|h| h.table.inv_cell_size == 1.0 / cell && h.refile(gpu, mesh, &[]));
        if refiled {
            uploads.overlay_filings += 1;
        }
        if stale && !refiled {
            let count = vertices.count;
            // Rows for every vertex there is room for: the overlay files new ones here.
            let positions = gpu.output_buffer::<Vec3>("hashed positions", capacity);
            let mut encoder = gpu.encoder("hash table");
            uploads.table_builds += 1;
            encoder.copy_buffer_to_buffer(
                &vertices.positions,
                0,
                &positions,
                0,
                (count * std::mem::size_of::<Vec3>()) as u64,
            );
            let table = GpuHashTable::record(
                gpu,
                &mut encoder,
                &positions,
                &vertices.flags,
                count,
                1.0 / cell,
                table_size_for(count),
            )?;
            gpu.submit(encoder);
            *slot = Some(Hashed {
                table,
                positions,
                marks: gpu.output_buffer::<u32>("overlay marks", capacity),
                drift: 0.0,
                overlay: None,
                moved: Vec::new(),
                filed_on_gpu: false,
                gpu_drift: None,
            });
        }
        Ok(())
    }

    /// Files every vertex that moved or changed since the main table was built — the
    /// overlay's members, the vertices moved since its filing (`moved`) and `changed` — in the
    /// overlay at its current position, and marks them: afterwards no vertex has drifted
    /// from where it is filed. O(those vertices), where a rebuild is O(every vertex). `false`
    /// when they pass [`overlay_limit`] (or the overlay's buffers the adapter's limits):
    /// rebuild the main table instead.
    pub(super) fn refile(&mut self, gpu: &GpuContext, mesh: &Mesh, changed: &[u32]) -> bool {
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
    pub(super) fn start_gpu_filing(
        &mut self,
        gpu: &GpuContext,
        room: usize,
    ) -> Result<(), GpuError> {
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
    pub(super) fn record_gpu_table(
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
    pub(super) fn record_gpu_filing(
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
    pub(super) fn check(&self, gpu: &GpuContext, mesh: &Mesh) -> Result<(), String> {
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
    pub(super) fn note_moved(
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
    pub(super) fn overlay(&self) -> Option<OverlayBuffers<'_>> {
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

/// The cell size the pipeline's grid uses (the table is built with the same).
pub(super) fn cell_size(state: &StrokeState<'_>) -> f32 {
    state.grid.map_or(state.max_edge, |g| g.cell_size())
}
