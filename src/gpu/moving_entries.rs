//! Host side of `wgsl/moving_entries.wgsl`: a step's moving entries and exclusion rings built
//! on the GPU from the selection list, so that no step has to wait for the host to build them.

use glam::Vec3;

use super::{GpuContext, GpuError, PackedTopology};
use crate::abi::{ENTRIES_WORKGROUP_SIZE, EntryParams, MovingVertex, SelectedVertex};
use crate::mesh::Mesh;

/// Words of room per entry for its exclusion ring. A ring of three on a mesh of valence six
/// holds 37 vertices, of four (the largest `exclusion_ring` gives) 61; a ring past the room is
/// counted as an overflow and the host builds that step's rings.
pub const RING_STRIDE: u32 = 64;

/// What `moving_entries` reads besides its parameters.
pub struct EntryBuffers<'a> {
    pub positions: &'a wgpu::Buffer,
    pub layers: &'a wgpu::Buffer,
    /// The selection list and its count (`GpuSelection`).
    pub selected: &'a wgpu::Buffer,
    pub selection_count: &'a wgpu::Buffer,
    /// [`PackedTopology`] words (paged).
    pub topology: &'a wgpu::Buffer,
}

/// Where `moving_entries` writes: one [`MovingVertex`] and [`RING_STRIDE`] ring words per
/// slot, and the count of rings cut short (to be cleared before).
pub struct BuiltEntryBuffers<'a> {
    pub moving: &'a wgpu::Buffer,
    pub rings: &'a wgpu::Buffer,
    pub overflows: &'a wgpu::Buffer,
}

/// The parameters for `capacity` slots, rings of graph distance `ring`, topology rows from
/// `vertex_rows_base`.
pub fn entry_params(capacity: usize, ring: u32, vertex_rows_base: u32) -> EntryParams {
    EntryParams {
        capacity: capacity as u32,
        ring,
        ring_stride: RING_STRIDE,
        vertex_rows_base,
    }
}

/// Bytes of the rings of `capacity` slots.
pub fn ring_bytes(capacity: usize) -> u64 {
    capacity as u64 * RING_STRIDE as u64 * 4
}

/// Records the pass writing `params.capacity` entries and their rings.
pub fn record_moving_entries(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    inputs: &EntryBuffers<'_>,
    params: &EntryParams,
    out: &BuiltEntryBuffers<'_>,
) -> Result<(), GpuError> {
    let pipeline = gpu.compute_pipeline("moving_entries")?;
    let uniform = gpu.uniform_buffer("moving_entries params", params);
    gpu.record_paged_dispatch(
        encoder,
        &pipeline,
        "moving_entries",
        &[
            &uniform,
            inputs.positions,
            inputs.layers,
            inputs.selected,
            inputs.selection_count,
            out.moving,
            out.rings,
            out.overflows,
        ],
        &[inputs.topology],
        super::Workgroups::Cover {
            invocations: params.capacity as usize,
            workgroup_size: ENTRIES_WORKGROUP_SIZE,
        },
    );
    Ok(())
}

/// What one run built: the entries, every slot's ring words, and the rings cut short.
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltEntries {
    pub moving: Vec<MovingVertex>,
    pub rings: Vec<u32>,
    pub overflows: u32,
}

/// Builds on the GPU the entries of the first `capacity` slots of `selected` (the list a
/// selection left, unsorted), rings of graph distance `ring` in `ring_stride` words each, over
/// `mesh` uploaded afresh.
pub fn run_moving_entries(
    gpu: &GpuContext,
    mesh: &Mesh,
    selected: &[SelectedVertex],
    (capacity, ring, ring_stride): (usize, u32, u32),
) -> Result<BuiltEntries, GpuError> {
    let topology = PackedTopology::of(mesh);
    let params = EntryParams {
        ring_stride,
        ..entry_params(capacity, ring, topology.layout.vertex_rows_base)
    };
    let positions: &[Vec3] = mesh.positions();
    let positions = gpu.storage_buffer("positions", positions, false);
    let layers = gpu.storage_buffer("layers", mesh.vertex_layers(), false);
    let list = gpu.storage_buffer("selected", selected, false);
    let count = gpu.storage_buffer("selection count", &[selected.len() as u32], false);
    let topology = topology.upload(gpu)?;
    let moving = gpu.output_buffer::<MovingVertex>("moving", capacity);
    let words = capacity * ring_stride as usize;
    let rings = gpu.output_buffer::<u32>("rings", words);
    let overflows = gpu.output_buffer::<u32>("ring overflows", 1);
    let mut encoder = gpu.encoder("moving_entries");
    record_moving_entries(
        gpu,
        &mut encoder,
        &EntryBuffers {
            positions: &positions,
            layers: &layers,
            selected: &list,
            selection_count: &count,
            topology: &topology,
        },
        &params,
        &BuiltEntryBuffers {
            moving: &moving,
            rings: &rings,
            overflows: &overflows,
        },
    )?;
    gpu.submit(encoder);
    Ok(BuiltEntries {
        moving: gpu.read_buffer(&moving, capacity)?,
        rings: gpu.read_buffer(&rings, words)?,
        overflows: gpu.read_buffer::<u32>(&overflows, 1)?[0],
    })
}
