//! Host side of `wgsl/select.wgsl`: brush selection through the GPU hash table into a compact
//! list of (vertex, falloff weight), in the order the append atomics ran in.

use glam::Vec3;

use super::overlay::{Filing, OverlayBuffers, TableBuffers, overlay_table};
use super::reusable::ReusableBuffer;
use super::{GpuContext, GpuError, GpuHashTable, VertexBuffers, table_size_for};
use crate::abi::{BrushSphere, SelectParams, SelectedVertex, WORKGROUP_SIZE, falloff_code};
use crate::grid::cell_coordinates;

/// Entries read back with the count when nothing better is known.
pub const SELECTION_GUESS: usize = 256;

/// The kernel's parameters: one invocation per cell of the brush's box (grown by `drift`, how
/// far any vertex has moved since the table was built), or per vertex when the box has more
/// cells than there are vertices (or more than a `u32` counts).
pub fn select_params(
    brush: &BrushSphere,
    drift: f32,
    inv_cell_size: f32,
    table_size: u32,
    vertex_count: usize,
    layer_count: usize,
) -> SelectParams {
    // 1 % on the drift so that rounding never leaves a moved vertex's cell out.
    let reach = brush.radius + 1.01 * drift;
    let lo = cell_coordinates(brush.center - reach, inv_cell_size);
    let hi = cell_coordinates(brush.center + reach, inv_cell_size);
    let span = (hi - lo).as_i64vec3() + 1;
    let cells = span.x.max(0) * span.y.max(0) * span.z.max(0);
    let scan_vertices = cells > vertex_count as i64;
    let (falloff, blend_n, blend_inner) = falloff_code(brush.falloff);
    SelectParams {
        center: brush.center.to_array(),
        radius: brush.radius,
        cell_min: lo.to_array(),
        table_mask: table_size - 1,
        cell_span: if scan_vertices {
            [0; 3]
        } else {
            span.as_uvec3().to_array()
        },
        inv_cell_size,
        candidate_count: if scan_vertices {
            vertex_count as u32
        } else {
            cells as u32
        },
        scan_vertices: scan_vertices as u32,
        falloff,
        blend_n,
        capacity: vertex_count as u32,
        layer_count: layer_count as u32,
        drift,
        skip_marked: 0,
        blend_inner,
        _pad0: 0,
        _pad1: 0,
        _pad2: 0,
    }
}

/// The selection's GPU buffers. `count` (one `u32`) may exceed the capacity after an overflow
/// (never with capacity = vertex count: a vertex is reported at most once); it is the input a
/// later pass turns into indirect dispatch sizes.
pub struct GpuSelection {
    pub capacity: usize,
    pub selected: wgpu::Buffer,
    pub count: wgpu::Buffer,
}

impl GpuSelection {
    pub fn new(gpu: &GpuContext, capacity: usize) -> Result<GpuSelection, GpuError> {
        gpu.check_binding::<SelectedVertex>("selection", capacity)?;
        Ok(GpuSelection {
            capacity,
            selected: gpu.output_buffer::<SelectedVertex>("selected", capacity),
            count: gpu.output_buffer::<u32>("selection count", 1),
        })
    }

    /// Submits `encoder`, which recorded a selection into these buffers (and whatever else),
    /// and reads back in one map the count, the first `guess` entries and the `extra` parts
    /// (`ReusableBuffer::read_back_parts`); a longer list costs a second read. Each blocking
    /// read-back is milliseconds on lavapipe: reading the count, then the list, was most of the
    /// GPU path's selection time.
    pub fn submit_and_read(
        &self,
        gpu: &GpuContext,
        encoder: wgpu::CommandEncoder,
        staging: &mut ReusableBuffer,
        guess: usize,
        extra: &[(&wgpu::Buffer, u64)],
    ) -> Result<SelectionRead, GpuError> {
        let entry = std::mem::size_of::<SelectedVertex>();
        let guess = guess.min(self.capacity);
        let mut parts = vec![(&self.count, 4), (&self.selected, (entry * guess) as u64)];
        parts.extend_from_slice(extra);
        let bytes = staging.read_back_parts(gpu, encoder, &parts)?;
        let count = (u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as usize)
            .min(self.capacity);
        let head = count.min(guess);
        let mut list: Vec<SelectedVertex> =
            bytemuck::pod_collect_to_vec(&bytes[4..4 + entry * head]);
        if count > head {
            let all: Vec<SelectedVertex> = gpu.read_buffer(&self.selected, count)?;
            list.extend_from_slice(&all[head..]);
        }
        Ok(SelectionRead {
            list,
            head,
            extra: bytes[4 + entry * guess..].to_vec(),
        })
    }
}

/// What [`GpuSelection::submit_and_read`] brought back.
pub struct SelectionRead {
    /// The whole list, in the order the kernel appended it.
    pub list: Vec<SelectedVertex>,
    /// How many of its entries came with the first map (the rest took a second read).
    pub head: usize,
    /// The extra parts' bytes, one after another.
    pub extra: Vec<u8>,
}

/// The selection list and its count with the per-vertex data the kernels read for each entry
/// (`brush_frame`, `deform`).
pub struct SelectionBuffers<'a> {
    pub positions: &'a wgpu::Buffer,
    pub normals: &'a wgpu::Buffer,
    pub selected: &'a wgpu::Buffer,
    /// One `u32`: the selection count (`GpuSelection::count`).
    pub selection_count: &'a wgpu::Buffer,
}

/// A hash table and the positions it was built from, with how far any vertex has moved since.
pub struct HashedVertices<'a> {
    pub table: &'a GpuHashTable,
    /// Packed positions at the build (may be the current positions buffer); the overlay's
    /// members at their filing.
    pub positions: &'a wgpu::Buffer,
    pub drift: f32,
    /// Vertices filed apart from `table` (`super::overlay`), if any.
    pub overlay: Option<OverlayBuffers<'a>>,
}

/// Records a selection into `selection` (its counter is cleared first).
#[allow(clippy::too_many_arguments)]
pub fn record_select(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    vertices: &VertexBuffers,
    active_layers: &wgpu::Buffer,
    layer_count: usize,
    hashed: &HashedVertices<'_>,
    brush: &BrushSphere,
    selection: &GpuSelection,
) -> Result<(), GpuError> {
    let table = hashed.table;
    let mut params = select_params(
        brush,
        hashed.drift,
        table.inv_cell_size,
        table.table_size,
        vertices.count,
        layer_count,
    );
    params.capacity = selection.capacity as u32;
    let pipeline = gpu.compute_pipeline("select")?;
    encoder.clear_buffer(&selection.count, 0, None);
    // A scan tests every vertex by its current position: the tables do not matter.
    let overlay = hashed.overlay.filter(|_| params.scan_vertices == 0);
    let main = TableBuffers {
        table_size: table.table_size,
        offsets: &table.offsets,
        entries: &table.entries,
    };
    // Without an overlay the marks are never read; the flags stand in for them.
    let marks = overlay.map_or(&vertices.flags, |o| o.marks);
    let walks = std::iter::once((main, overlay.is_some())).chain(overlay.map(|o| (o.table, false)));
    for (walked, skip_marked) in walks {
        let params = SelectParams {
            table_mask: walked.table_size - 1,
            skip_marked: skip_marked as u32,
            ..params
        };
        let uniform = gpu.uniform_buffer("select params", &params);
        gpu.record_dispatch(
            encoder,
            &pipeline,
            "select",
            &[
                &uniform,
                &vertices.positions,
                &vertices.layers,
                &vertices.flags,
                active_layers,
                walked.offsets,
                walked.entries,
                &selection.selected,
                &selection.count,
                hashed.positions,
                marks,
            ],
            params.candidate_count as usize,
            WORKGROUP_SIZE,
        );
    }
    Ok(())
}

/// Builds the hash table (cells of `1 / inv_cell_size`) of the `hashed` positions and selects
/// under `brush` at `positions` (vertices may have moved since they were hashed), on the GPU.
#[allow(clippy::too_many_arguments)]
pub fn run_select(
    gpu: &GpuContext,
    hashed: &[Vec3],
    positions: &[Vec3],
    layers: &[u32],
    flags: &[u32],
    active: &[bool],
    inv_cell_size: f32,
    brush: &BrushSphere,
) -> Result<Vec<SelectedVertex>, GpuError> {
    let vertices = (positions, layers, flags);
    run_select_with_overlay(gpu, hashed, vertices, active, inv_cell_size, brush, &[])
}

/// [`run_select`] with `members` (ascending vertex ids) filed in an overlay at their current
/// positions, as the GPU backend files the vertices remeshing changed; their `hashed` positions
/// are stale (and may be anything).
#[allow(clippy::too_many_arguments)]
pub fn run_select_with_overlay(
    gpu: &GpuContext,
    hashed: &[Vec3],
    (positions, layers, flags): (&[Vec3], &[u32], &[u32]),
    active: &[bool],
    inv_cell_size: f32,
    brush: &BrushSphere,
    members: &[u32],
) -> Result<Vec<SelectedVertex>, GpuError> {
    assert_eq!(
        hashed.len(),
        positions.len(),
        "one hashed position per vertex"
    );
    // The main table is built from the stale positions; the overlay's members are filed (and
    // their filing positions recorded) where they are now.
    let Filing {
        filed_at,
        marks,
        drift,
    } = Filing::of(hashed, positions, members);
    let filed = VertexBuffers::upload(gpu, hashed, layers, flags)?;
    let filed_positions = gpu.storage_buffer("filed positions", &filed_at, false);
    let overlay_table = overlay_table(positions, members, inv_cell_size);
    let overlay_offsets = gpu.storage_buffer("overlay offsets", &overlay_table.offsets, false);
    let overlay_entries = gpu.storage_buffer("overlay entries", &overlay_table.entries, false);
    let marks = gpu.storage_buffer("overlay marks", &marks, false);
    let overlay = (!members.is_empty()).then_some(OverlayBuffers {
        table: TableBuffers {
            table_size: overlay_table.table_size() as u32,
            offsets: &overlay_offsets,
            entries: &overlay_entries,
        },
        marks: &marks,
    });
    let vertices = VertexBuffers::upload(gpu, positions, layers, flags)?;
    let active: Vec<u32> = active.iter().map(|&a| a as u32).collect();
    let active_buffer = gpu.storage_buffer("active layers", &active, false);
    let selection = GpuSelection::new(gpu, positions.len())?;
    let mut encoder = gpu.encoder("select");
    let table = GpuHashTable::record(
        gpu,
        &mut encoder,
        &filed.positions,
        &filed.flags,
        filed.count,
        inv_cell_size,
        table_size_for(filed.count),
    )?;
    record_select(
        gpu,
        &mut encoder,
        &vertices,
        &active_buffer,
        active.len(),
        &HashedVertices {
            table: &table,
            positions: &filed_positions,
            drift,
            overlay,
        },
        brush,
        &selection,
    )?;
    let mut staging = ReusableBuffer::readback("selection read-back");
    Ok(selection
        .submit_and_read(gpu, encoder, &mut staging, SELECTION_GUESS, &[])?
        .list)
}
