//! A small second hash table for the vertices remeshing changed, so that the main table need
//! not be rebuilt after every stroke. Rebuilding the main table is a pass over every vertex —
//! at 16M faces on lavapipe 2.2 s, most of a stroke — while remeshing changes a few thousand.
//! Those vertices (new ones among them) are filed in the overlay at their current positions and
//! marked; queries walk the main table leaving marked vertices out (their entries there are
//! stale, or missing for new vertices) and then the overlay. The overlay is built on the CPU
//! with the hash table's mirror (`crate::cpu::hash_table`) — a few thousand entries — and grows
//! stroke by stroke until the main table is rebuilt (drift, or the overlay passing
//! [`overlay_limit`]), which empties it.
//!
//! Between the samples of a stroke recorded in one submission the host cannot refile, so the
//! GPU does (`wgsl/shared/overlay.wgsl`): the overlay's members sit in slots, `overlay_members`
//! files a step's moved vertices there, and the table is rebuilt from the slots by the hash
//! build's counting sort ([`record_overlay_table`]). The marks are then slot + 1, which the host
//! filing writes too (its members ascending).

use glam::Vec3;

use super::hash_table::{read_table, record_counting_sort};
use super::reusable::ReusableBuffer;
use super::{GpuContext, GpuError, table_size_for};
use crate::abi::{CsrTable, MovingVertex, OverlayParams, WORKGROUP_SIZE};
use crate::cpu::OverlaySlots;

/// Vertices the overlay holds before the main table is rebuilt instead: a sixteenth of the
/// mesh. Filing is CPU work proportional to the overlay, at every refiling; a rebuild is GPU
/// work proportional to the mesh. Plaster on lavapipe, 40 strokes at 100K faces: selection
/// took 8.9–9.0 s with an overlay allowed to hold the whole mesh, 8.2–8.6 s with this limit
/// (37 rebuilds), 6.0–7.4 s rebuilding at every drift as before the overlay (small meshes
/// rebuild cheaply); at 16M faces a rebuild is 2.2 s and the overlay made a sample 16 times
/// cheaper.
pub fn overlay_limit(vertex_count: usize) -> usize {
    (vertex_count / 16).max(1024)
}

/// The table of `members` (vertex ids, ascending) at `positions`, in cells of
/// `1 / inv_cell_size`: entries are vertex ids, as in the main table.
pub fn overlay_table(positions: &[Vec3], members: &[u32], inv_cell_size: f32) -> CsrTable {
    let table_size = table_size_for(members.len());
    overlay_table_sized(positions, members, inv_cell_size, table_size)
}

/// [`overlay_table`] in `table_size` buckets.
pub fn overlay_table_sized(
    positions: &[Vec3],
    members: &[u32],
    inv_cell_size: f32,
    table_size: u32,
) -> CsrTable {
    let filed: Vec<Vec3> = members.iter().map(|&v| positions[v as usize]).collect();
    // Dead vertices stay filed: queries read the flags and leave them out.
    let alive = vec![0u32; members.len()];
    let mut table = crate::cpu::hash_table(&filed, &alive, inv_cell_size, table_size);
    for entry in &mut table.entries {
        *entry = members[*entry as usize];
    }
    table
}

/// Where queries find each vertex when `members` are filed in the overlay at `positions` and
/// the others where the main table filed them (`hashed`).
pub struct Filing {
    /// Per vertex: the position it is filed at.
    pub filed_at: Vec<Vec3>,
    /// Per vertex: 1 for members.
    pub marks: Vec<u32>,
    /// How far any other vertex has moved since the main table filed it.
    pub drift: f32,
}

impl Filing {
    pub fn of(hashed: &[Vec3], positions: &[Vec3], members: &[u32]) -> Filing {
        let mut filed_at = hashed.to_vec();
        let mut marks = vec![0u32; positions.len()];
        for &v in members {
            filed_at[v as usize] = positions[v as usize];
            marks[v as usize] = 1;
        }
        let drift = (0..positions.len())
            .filter(|&v| marks[v] == 0)
            .map(|v| hashed[v].distance(positions[v]))
            .fold(0.0f32, f32::max);
        Filing {
            filed_at,
            marks,
            drift,
        }
    }
}

/// The buckets of a table a query walks (the main table's or the overlay's).
#[derive(Clone, Copy)]
pub struct TableBuffers<'a> {
    pub table_size: u32,
    pub offsets: &'a wgpu::Buffer,
    pub entries: &'a wgpu::Buffer,
}

/// The overlay as queries bind it, with the per-vertex marks of its members.
#[derive(Clone, Copy)]
pub struct OverlayBuffers<'a> {
    pub table: TableBuffers<'a>,
    /// Per vertex: nonzero for members.
    pub marks: &'a wgpu::Buffer,
}

/// The overlay's slots on the GPU (see `wgsl/shared/overlay.wgsl`): the members, their count,
/// and the rebuild's scratch (a key, a flag word and a rank per slot).
pub struct SlotBuffers {
    members: ReusableBuffer,
    member_count: ReusableBuffer,
    keys: ReusableBuffer,
    flags: ReusableBuffer,
    ranks: ReusableBuffer,
    room: usize,
}

impl Default for SlotBuffers {
    fn default() -> Self {
        SlotBuffers {
            members: ReusableBuffer::storage("overlay members"),
            member_count: ReusableBuffer::storage("overlay member count"),
            keys: ReusableBuffer::storage("overlay keys"),
            flags: ReusableBuffer::storage("overlay slot flags"),
            ranks: ReusableBuffer::storage("overlay ranks"),
            room: 0,
        }
    }
}

impl SlotBuffers {
    /// Room for `room` slots, the first holding `members` in order (the host filing's, whose
    /// marks are slot + 1), queued for upload.
    pub fn start(
        &mut self,
        gpu: &GpuContext,
        members: &[u32],
        room: usize,
    ) -> Result<(), GpuError> {
        debug_assert!(members.len() <= room);
        let bytes = (room.max(1) * 4) as u64;
        self.members.reserve(gpu, bytes)?;
        self.keys.reserve(gpu, bytes)?;
        self.flags.reserve(gpu, bytes)?;
        self.ranks.reserve(gpu, bytes)?;
        if !members.is_empty() {
            gpu.queue
                .write_buffer(self.members.buffer(), 0, bytemuck::cast_slice(members));
        }
        self.member_count.upload(gpu, &[members.len() as u32])?;
        self.room = room;
        Ok(())
    }

    pub fn room(&self) -> usize {
        self.room
    }
}

/// The per-vertex buffers the overlay's filing shares with the queries.
#[derive(Clone, Copy)]
pub struct Filed<'a> {
    /// Per vertex: slot + 1 for members.
    pub marks: &'a wgpu::Buffer,
    /// Per vertex, packed x, y, z: where it is filed.
    pub filed_at: &'a wgpu::Buffer,
}

fn overlay_params(
    count: usize,
    slots: &SlotBuffers,
    table_size: u32,
    inv_cell_size: f32,
) -> OverlayParams {
    OverlayParams {
        count: count as u32,
        room: slots.room as u32,
        table_mask: table_size - 1,
        inv_cell_size,
    }
}

/// Records `overlay_members` over the first `moving_slots` slots of `moving`: the entries away
/// from their start in `positions` are filed where they are, new members taking slots.
pub fn record_overlay_members(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (positions, moving, moving_slots): (&wgpu::Buffer, &wgpu::Buffer, usize),
    slots: &SlotBuffers,
    filed: Filed<'_>,
) -> Result<(), GpuError> {
    let params = overlay_params(moving_slots, slots, 1, 1.0);
    let pipeline = gpu.compute_pipeline("overlay_members")?;
    let uniform = gpu.uniform_buffer("overlay_members params", &params);
    gpu.record_dispatch(
        encoder,
        &pipeline,
        "overlay_members",
        &[
            &uniform,
            positions,
            moving,
            filed.marks,
            slots.members.buffer(),
            slots.member_count.buffer(),
            filed.filed_at,
        ],
        moving_slots,
        WORKGROUP_SIZE,
    );
    Ok(())
}

/// Records the rebuild of the overlay `table` (`table.table_size` buckets, `offsets` and
/// `entries` with room for them and for every slot) from the slots, each member in the cell
/// of where it is filed: `overlay_keys`, the hash build's counting sort over every slot of the
/// room, `overlay_entries`.
pub fn record_overlay_table(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    slots: &SlotBuffers,
    filed_at: &wgpu::Buffer,
    table: TableBuffers<'_>,
    inv_cell_size: f32,
) -> Result<(), GpuError> {
    let params = overlay_params(slots.room, slots, table.table_size, inv_cell_size);
    let uniform = gpu.uniform_buffer("overlay params", &params);
    let keys = gpu.compute_pipeline("overlay_keys")?;
    gpu.record_dispatch(
        encoder,
        &keys,
        "overlay_keys",
        &[
            &uniform,
            slots.members.buffer(),
            slots.member_count.buffer(),
            filed_at,
            slots.keys.buffer(),
            slots.flags.buffer(),
        ],
        slots.room,
        WORKGROUP_SIZE,
    );
    // The counts start from nothing.
    encoder.clear_buffer(table.offsets, 0, None);
    record_counting_sort(
        gpu,
        encoder,
        (
            slots.keys.buffer(),
            slots.flags.buffer(),
            slots.ranks.buffer(),
        ),
        (table.offsets, table.entries),
        slots.room,
        table.table_size,
    )?;
    let entries = gpu.compute_pipeline("overlay_entries")?;
    gpu.record_dispatch(
        encoder,
        &entries,
        "overlay_entries",
        &[
            &uniform,
            slots.members.buffer(),
            table.offsets,
            table.entries,
        ],
        slots.room,
        WORKGROUP_SIZE,
    );
    Ok(())
}

/// `overlay_members` on the GPU from `before` (room: its `members`' length), over `positions`
/// after a step: the slots after.
pub fn run_overlay_members(
    gpu: &GpuContext,
    positions: &[Vec3],
    moving: &[MovingVertex],
    before: &OverlaySlots,
) -> Result<OverlaySlots, GpuError> {
    gpu.check_binding::<Vec3>("vertex positions", positions.len())?;
    let room = before.members.len();
    let mut slots = SlotBuffers::default();
    slots.start(gpu, &before.members, room)?;
    slots.member_count.upload(gpu, &[before.member_count])?;
    let positions = gpu.storage_buffer("positions", positions, false);
    let moving_buffer = gpu.storage_buffer("moving list", moving, false);
    let marks = gpu.storage_buffer("overlay marks", &before.marks, true);
    let filed_at = gpu.storage_buffer("filed at", &before.filed_at, true);
    let mut encoder = gpu.encoder("overlay_members");
    let filed = Filed {
        marks: &marks,
        filed_at: &filed_at,
    };
    record_overlay_members(
        gpu,
        &mut encoder,
        (&positions, &moving_buffer, moving.len()),
        &slots,
        filed,
    )?;
    gpu.submit(encoder);
    Ok(OverlaySlots {
        marks: gpu.read_buffer(&marks, before.marks.len())?,
        members: gpu.read_buffer(slots.members.buffer(), room)?,
        member_count: gpu.read_buffer::<u32>(slots.member_count.buffer(), 1)?[0],
        filed_at: gpu.read_buffer(&filed_at, before.filed_at.len())?,
    })
}

/// The overlay table of `slots` (room: its `members`' length) in `table_size` buckets, rebuilt
/// on the GPU ([`record_overlay_table`]) and read back.
pub fn run_overlay_table(
    gpu: &GpuContext,
    slots: &OverlaySlots,
    table_size: u32,
    inv_cell_size: f32,
) -> Result<CsrTable, GpuError> {
    let room = slots.members.len();
    let mut buffers = SlotBuffers::default();
    buffers.start(gpu, &slots.members, room)?;
    buffers.member_count.upload(gpu, &[slots.member_count])?;
    let filed_at = gpu.storage_buffer("filed at", &slots.filed_at, false);
    let offsets = gpu.output_buffer::<u32>("overlay offsets", table_size as usize + 1);
    let entries = gpu.output_buffer::<u32>("overlay entries", room);
    let table = TableBuffers {
        table_size,
        offsets: &offsets,
        entries: &entries,
    };
    let mut encoder = gpu.encoder("overlay table");
    record_overlay_table(gpu, &mut encoder, &buffers, &filed_at, table, inv_cell_size)?;
    gpu.submit(encoder);
    read_table(gpu, (&offsets, &entries), table_size)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlay_entries_are_vertex_ids_in_their_cells() {
        let positions: Vec<Vec3> = (0..50).map(|i| Vec3::splat(i as f32 * 0.3)).collect();
        let members = [3u32, 17, 18, 40];
        let table = overlay_table(&positions, &members, 1.0);
        let mut filed = table.entries.clone();
        filed.sort_unstable();
        assert_eq!(filed, members);
        for &v in &members {
            let cell = crate::grid::cell_coordinates(positions[v as usize], 1.0);
            let bucket = crate::grid::hash_cell(cell, table.table_size() as u32);
            assert!(
                table.bucket(bucket).contains(&v),
                "vertex {v} in its cell's bucket"
            );
        }
    }
}
