//! Host side of `wgsl/proximity.wgsl`: one Jacobi pass of vertex–triangle proximity and
//! clamping over a step's selection, as `collide::pull_back` does it on the CPU. The
//! kernel leaves a pull-back amount per entry; [`verdicts`] turns amounts into positions as
//! `apply_moves` does on the GPU.
//!
//! What a GPU backend keeps between passes: the moving list and rings (built once per step on
//! the CPU: rings are connectivity, which only remeshing changes), the per-vertex marks (a
//! vertex pulled back in a pass marks its faces as changed for the next one, exactly the faces
//! the CPU's `changed` holds), and the positions with the pass's results written in.

use glam::Vec3;

use super::{GpuContext, GpuError, PackedTopology, Workgroups, table_size_for};
use crate::abi::{
    MovingVertex, PROXIMITY_WORKGROUP_SIZE, PULL_SCALE, ProximityParams, PulledVertex,
};
use crate::collide::neighbourhood::ring_vertices;
use crate::mesh::Mesh;

/// Margin on the broad phase's reaches so that rounding never drops a face exact arithmetic
/// keeps; extra candidates cost time, never results.
const REACH_SLACK: f32 = 1.01;

/// One moving entry per selected vertex (vertex `selection[i]` started the step at
/// `starts[i]`), with its exclusion ring appended to the returned ring list.
pub fn moving_vertices(
    mesh: &Mesh,
    selection: &[u32],
    starts: &[Vec3],
    ring: u32,
) -> (Vec<MovingVertex>, Vec<u32>) {
    assert_eq!(
        selection.len(),
        starts.len(),
        "one start per selected vertex"
    );
    let mut rings = Vec::new();
    let mut scratch = Vec::new();
    let moving = selection
        .iter()
        .zip(starts)
        .map(|(&v, start)| {
            ring_vertices(mesh, v, ring, &mut scratch);
            let ring_start = rings.len() as u32;
            rings.extend_from_slice(&scratch);
            MovingVertex {
                start: start.to_array(),
                vertex: v,
                layer: mesh.vertex_layers()[v as usize],
                ring_start,
                ring_end: rings.len() as u32,
                _pad: 0,
            }
        })
        .collect();
    (moving, rings)
}

/// Broad-phase reaches for collision distance `distance`, `max_edge` an upper bound on edge
/// lengths when the hash table was built, and `max_move` the farthest any vertex has moved
/// since. An edge grows by at most its two ends' moves, so a face within `distance` of a point
/// has every vertex within `distance + max_edge + 2·max_move` of it (the vertex reach), filed
/// at most `max_move` farther (the cell reach).
pub fn proximity_reaches(distance: f32, max_edge: f32, max_move: f32) -> (f32, f32) {
    let vertex_reach = distance + max_edge + 2.0 * max_move;
    (
        REACH_SLACK * (vertex_reach + max_move),
        REACH_SLACK * vertex_reach,
    )
}

/// Invocations per entry and their box of cells (x, y, z) for a search `cell_reach` around
/// the tentative position, with cells of `1 / inv_cell_size`: enough for any position.
pub fn cells_per_entry(cell_reach: f32, inv_cell_size: f32) -> ([u32; 3], u32) {
    let side = (2.0 * cell_reach * inv_cell_size).floor() as u32 + 2;
    ([side; 3], side * side * side)
}

/// The pulled-back position of each entry from the amounts a pass left (65536 − 65536·t, zero
/// when not pulled), `positions` the packed positions the pass saw: as `apply_moves` computes
/// them, and `pull_back` (`start + (x − start)·t`).
pub fn verdicts(moving: &[MovingVertex], positions: &[f32], pulls: &[u32]) -> Vec<PulledVertex> {
    moving
        .iter()
        .zip(pulls)
        .map(|(entry, &pull)| {
            let x = crate::cpu::packed_position(positions, entry.vertex);
            if pull == 0 {
                return PulledVertex {
                    position: x.to_array(),
                    pulled: 0,
                };
            }
            let start = Vec3::from_array(entry.start);
            let t = (65536 - pull) as f32 / PULL_SCALE;
            PulledVertex {
                position: (start + (x - start) * t).to_array(),
                pulled: 1,
            }
        })
        .collect()
}

/// Buffers `proximity` binds besides its parameters and output.
pub struct ProximityBuffers<'a> {
    /// Current packed positions (targets written in).
    pub positions: &'a wgpu::Buffer,
    /// The hash table's `offsets` and `entries` (`GpuHashTable`).
    pub offsets: &'a wgpu::Buffer,
    pub entries: &'a wgpu::Buffer,
    /// [`PackedTopology`] words (paged).
    pub topology: &'a wgpu::Buffer,
    pub moving: &'a wgpu::Buffer,
    /// Paged.
    pub rings: &'a wgpu::Buffer,
    /// Per-vertex marks; any buffer when `params.all_faces` is 1.
    pub marks: &'a wgpu::Buffer,
    /// The overlay table: per vertex nonzero when filed there, its offsets and entries; any
    /// buffers unless `params.overlay`.
    pub overlay_marks: &'a wgpu::Buffer,
    pub overlay_offsets: &'a wgpu::Buffer,
    pub overlay_entries: &'a wgpu::Buffer,
}

/// Records one pass folding into `pulls[i]` (zero beforehand) the pull-back amount of each of
/// the `params.count` moving entries; `params.count · params.cells_per_entry` invocations,
/// sized on the host, or by the GPU from `indirect` (three workgroup counts) when given.
pub fn record_proximity(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    inputs: &ProximityBuffers<'_>,
    params: &ProximityParams,
    pulls: &wgpu::Buffer,
    indirect: Option<&wgpu::Buffer>,
) -> Result<(), GpuError> {
    let pipeline = gpu.compute_pipeline("proximity")?;
    let uniform = gpu.uniform_buffer("proximity params", params);
    let resources = [
        &uniform,
        inputs.positions,
        inputs.offsets,
        inputs.entries,
        inputs.moving,
        inputs.marks,
        pulls,
        inputs.overlay_marks,
        inputs.overlay_offsets,
        inputs.overlay_entries,
    ];
    let workgroups = match indirect {
        Some(args) => Workgroups::Indirect(args),
        None => Workgroups::Cover {
            invocations: params.count as usize * params.cells_per_entry as usize,
            workgroup_size: PROXIMITY_WORKGROUP_SIZE,
        },
    };
    gpu.record_paged_dispatch(
        encoder,
        &pipeline,
        "proximity",
        &resources,
        &[inputs.topology, inputs.rings],
        workgroups,
    );
    Ok(())
}

/// Fails clearly when a pass would need more invocations than a `u32` counts.
pub fn check_invocations(params: &ProximityParams) -> Result<(), GpuError> {
    check_entry_invocations("a proximity pass", params.count, params.cells_per_entry)
}

/// Fails clearly when `what`, `count` entries of `per_entry` invocations each, would need more
/// invocations than a `u32` counts (the kernels' flat index).
pub(super) fn check_entry_invocations(
    what: &str,
    count: u32,
    per_entry: u32,
) -> Result<(), GpuError> {
    let invocations = count as u64 * per_entry as u64;
    if invocations > u32::MAX as u64 {
        return Err(GpuError::TooLarge {
            what: format!("{what} ({count} moving vertices × {per_entry} invocations)"),
            bytes: invocations,
            limit: u32::MAX as u64,
        });
    }
    Ok(())
}

/// One proximity pass, everything taken from the CPU.
pub struct ProximityQuery<'a> {
    /// The mesh at the start of the step: its positions are the ones hashed and the starts.
    pub mesh: &'a Mesh,
    /// Per vertex: where it is now (the selection at its targets).
    pub current: &'a [Vec3],
    pub selection: &'a [u32],
    pub distance: f32,
    /// Exclusion ring (graph distance).
    pub ring: u32,
    /// Upper bound on edge lengths at the step's start.
    pub max_edge: f32,
    pub cell_size: f32,
    /// Per vertex: nonzero where pulled back in the last pass; `None` tests every face.
    pub marks: Option<&'a [u32]>,
}

/// The parameters of `query`'s pass over `count` entries.
pub fn proximity_params(
    query: &ProximityQuery<'_>,
    vertex_rows_base: u32,
    table_size: u32,
) -> ProximityParams {
    let positions = query.mesh.positions();
    let max_move = query
        .selection
        .iter()
        .map(|&v| positions[v as usize].distance(query.current[v as usize]))
        .fold(0.0f32, f32::max);
    ProximityParams {
        all_faces: query.marks.is_none() as u32,
        ..pass_params(
            (query.distance, query.max_edge, max_move),
            1.0 / query.cell_size,
            table_size,
            query.selection.len(),
            vertex_rows_base,
        )
    }
}

/// The parameters of a first pass (every face) over `count` entries, for collision distance,
/// edge bound and move bound `(distance, max_edge, max_move)` as [`proximity_reaches`] takes
/// them, a table of `table_size` buckets of `1 / inv_cell_size` cells, and topology rows from
/// `vertex_rows_base`.
pub fn pass_params(
    (distance, max_edge, max_move): (f32, f32, f32),
    inv_cell_size: f32,
    table_size: u32,
    count: usize,
    vertex_rows_base: u32,
) -> ProximityParams {
    let (cell_reach, vertex_reach) = proximity_reaches(distance, max_edge, max_move);
    let (span, cells) = cells_per_entry(cell_reach, inv_cell_size);
    ProximityParams {
        distance,
        cell_reach,
        vertex_reach,
        inv_cell_size,
        table_mask: table_size - 1,
        count: count as u32,
        vertex_rows_base,
        all_faces: 1,
        span,
        cells_per_entry: cells,
        overlay: 0,
        overlay_mask: 0,
        _pad0: 0,
        _pad1: 0,
    }
}

/// Builds the hash table of the step's start positions and runs one pass on the GPU.
pub fn run_proximity(
    gpu: &GpuContext,
    query: &ProximityQuery<'_>,
) -> Result<Vec<PulledVertex>, GpuError> {
    let mesh = query.mesh;
    assert_eq!(
        query.current.len(),
        mesh.vertex_count(),
        "one position per vertex"
    );
    let starts: Vec<Vec3> = query
        .selection
        .iter()
        .map(|&v| mesh.positions()[v as usize])
        .collect();
    let (moving, rings) = moving_vertices(mesh, query.selection, &starts, query.ring);
    let topology = PackedTopology::of(mesh);
    let table_size = table_size_for(mesh.vertex_count());
    let params = proximity_params(query, topology.layout.vertex_rows_base, table_size);
    check_invocations(&params)?;
    gpu.check_paged("exclusion rings", rings.len())?;
    let hashed = super::VertexBuffers::upload(
        gpu,
        mesh.positions(),
        mesh.vertex_layers(),
        &mesh.flags().iter().map(|f| f.bits()).collect::<Vec<_>>(),
    )?;
    let current = gpu.storage_buffer("current positions", query.current, false);
    let topology = topology.upload(gpu)?;
    let moving_list = moving;
    let moving = gpu.storage_buffer("moving", &moving_list, false);
    let rings = gpu.storage_buffer("rings", &rings, false);
    let marks = gpu.storage_buffer("marks", query.marks.unwrap_or(&[]), false);
    let pulls = gpu.output_buffer::<u32>("pulls", query.selection.len());
    let mut encoder = gpu.encoder("proximity");
    let table = super::GpuHashTable::record(
        gpu,
        &mut encoder,
        &hashed.positions,
        &hashed.flags,
        mesh.vertex_count(),
        params.inv_cell_size,
        table_size,
    )?;
    record_proximity(
        gpu,
        &mut encoder,
        &ProximityBuffers {
            positions: &current,
            offsets: &table.offsets,
            entries: &table.entries,
            topology: &topology,
            moving: &moving,
            rings: &rings,
            marks: &marks,
            // No overlay: unread.
            overlay_marks: &marks,
            overlay_offsets: &marks,
            overlay_entries: &marks,
        },
        &params,
        &pulls,
        None,
    )?;
    gpu.submit(encoder);
    let pulls: Vec<u32> = gpu.read_buffer(&pulls, query.selection.len())?;
    Ok(verdicts(
        &moving_list,
        bytemuck::cast_slice(query.current),
        &pulls,
    ))
}
