//! Host side of `wgsl/backstop_filter.wgsl`: the f32 filter in front of the exact backstop. After a
//! step's proximity passes it lists the pairs of faces (a moved face and another, or a moved
//! face and itself for "may have turned over") that it cannot clear; the CPU decides those
//! with the exact predicates (`collide::Backstop::Undecided`) instead of gathering
//! and searching the step's region.

use glam::Vec3;

use super::{
    GpuContext, GpuError, PackedTopology, Workgroups, cells_per_entry, moving_vertices,
    table_size_for,
};
use crate::abi::{BACKSTOP_WORKGROUP_SIZE, BackstopParams, MovingVertex};
use crate::mesh::Mesh;

/// Margin on the reaches, as the proximity kernel's: rounding never drops a candidate.
const REACH_SLACK: f32 = 1.01;

/// Room for undecided pairs when nothing better is known: most steps have none or a few.
pub const PAIRS_GUESS: usize = 1024;

/// The parameters of a filter over `count` entries. `edges`: `max_edge`, an upper bound on
/// edge lengths at the step's start, and `moved_edge`, one on the edges of moved faces after
/// the step ([`moved_edge_bound`]); `moves`: `drift`, how far any vertex had moved from where
/// the table filed it at the step's start, and `step_move`, the farthest the step moved one; a
/// table of `table_size` buckets of `1 / inv_cell_size` cells; topology rows from
/// `vertex_rows_base`; room for `capacity` pairs.
///
/// A face crossing a moved face f meets it within one of f's edges of f's moved vertex x, and
/// has every vertex within one of its own edges of there: within `moved_edge + max(max_edge,
/// moved_edge)` of x (the vertex reach), filed at most `drift + step_move` farther (the cell
/// reach); and within one edge and that drift of the box of f (the face reach).
pub fn backstop_params(
    (max_edge, moved_edge): (f32, f32),
    (drift, step_move): (f32, f32),
    (inv_cell_size, table_size): (f32, u32),
    count: usize,
    vertex_rows_base: u32,
    capacity: usize,
) -> BackstopParams {
    let longest = max_edge.max(moved_edge);
    let vertex_reach = REACH_SLACK * (moved_edge + longest);
    let cell_reach = REACH_SLACK * (vertex_reach + drift + step_move);
    let face_reach = REACH_SLACK * (longest + drift + step_move);
    // An invocation walks a row of cells along x.
    let (span, _) = cells_per_entry(cell_reach, inv_cell_size);
    BackstopParams {
        cell_reach,
        vertex_reach,
        inv_cell_size,
        table_mask: table_size - 1,
        count: count as u32,
        vertex_rows_base,
        cells_per_entry: span[1] * span[2],
        capacity: capacity as u32,
        span,
        overlay: 0,
        overlay_mask: 0,
        face_reach,
        _pad1: 0,
        _pad2: 0,
    }
}

/// An upper bound on the length, after the step, of every edge of a face around a vertex of
/// `selection` (ascending), each of which moves somewhere on the segment from `starts[i]` to
/// `ends[i]` (the proximity passes only shorten a move): an edge's length is convex in its two
/// ends, so its largest is at the segments' ends.
pub fn moved_edge_bound(mesh: &Mesh, selection: &[u32], starts: &[Vec3], ends: &[Vec3]) -> f32 {
    let reach = |w: u32| -> [Vec3; 2] {
        match selection.binary_search(&w) {
            Ok(i) => [starts[i], ends[i]],
            Err(_) => [mesh.positions()[w as usize]; 2],
        }
    };
    let mut longest = 0.0f32;
    for &v in selection {
        for f in mesh.faces_around(v) {
            let corners = mesh.faces()[f as usize].map(reach);
            for k in 0..3 {
                let (a, b) = (corners[k], corners[(k + 1) % 3]);
                for p in a {
                    for q in b {
                        longest = longest.max(p.distance(q));
                    }
                }
            }
        }
    }
    longest
}

/// Fails clearly when a filter would need more invocations than a `u32` counts.
pub fn check_backstop_invocations(params: &BackstopParams) -> Result<(), GpuError> {
    super::proximity::check_entry_invocations(
        "a backstop filter",
        params.count,
        params.cells_per_entry,
    )
}

/// Buffers `backstop` binds besides its parameters and outputs.
pub struct BackstopBuffers<'a> {
    /// Packed positions after the proximity passes.
    pub positions: &'a wgpu::Buffer,
    /// The hash table's `offsets` and `entries`.
    pub offsets: &'a wgpu::Buffer,
    pub entries: &'a wgpu::Buffer,
    /// [`PackedTopology`] words (paged).
    pub topology: &'a wgpu::Buffer,
    pub moving: &'a wgpu::Buffer,
    /// Per vertex: the entry + 1 where the step moved it (`ApplyMode::MarkMoved`), else zero.
    pub moved: &'a wgpu::Buffer,
    /// The overlay table, as [`super::ProximityBuffers`] has it.
    pub overlay_marks: &'a wgpu::Buffer,
    pub overlay_offsets: &'a wgpu::Buffer,
    pub overlay_entries: &'a wgpu::Buffer,
}

/// Records the filter: undecided pairs into `pairs` (two words each, up to `params.capacity`),
/// all of them counted in `pair_count` (zero beforehand).
pub fn record_backstop_filter(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    inputs: &BackstopBuffers<'_>,
    params: &BackstopParams,
    (pairs, pair_count): (&wgpu::Buffer, &wgpu::Buffer),
) -> Result<(), GpuError> {
    check_backstop_invocations(params)?;
    let pipeline = gpu.compute_pipeline("backstop_filter")?;
    let uniform = gpu.uniform_buffer("backstop params", params);
    let resources = [
        &uniform,
        inputs.positions,
        inputs.offsets,
        inputs.entries,
        inputs.moving,
        inputs.moved,
        pairs,
        pair_count,
        inputs.overlay_marks,
        inputs.overlay_offsets,
        inputs.overlay_entries,
    ];
    gpu.record_paged_dispatch(
        encoder,
        &pipeline,
        "backstop_filter",
        &resources,
        &[inputs.topology],
        Workgroups::Cover {
            invocations: params.count as usize * params.cells_per_entry as usize,
            workgroup_size: BACKSTOP_WORKGROUP_SIZE,
        },
    );
    Ok(())
}

/// One filter, everything taken from the CPU.
pub struct BackstopQuery<'a> {
    /// The mesh at the start of the step: its positions are the ones hashed and the starts.
    pub mesh: &'a Mesh,
    /// Per vertex: where it is after the step.
    pub current: &'a [Vec3],
    /// The step's selection, ascending.
    pub selection: &'a [u32],
    /// Upper bound on edge lengths at the step's start.
    pub max_edge: f32,
    pub cell_size: f32,
    /// Room for pairs.
    pub capacity: usize,
}

/// What a filter found: the pairs kept and how many there were (more than kept on overflow).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UndecidedPairs {
    pub pairs: Vec<[u32; 2]>,
    pub count: u32,
}

/// The moving list of `query` (rings empty: the filter reads none) and the per-vertex map
/// `ApplyMode::MarkMoved` leaves.
pub fn backstop_inputs(query: &BackstopQuery<'_>) -> (Vec<MovingVertex>, Vec<u32>) {
    let mesh = query.mesh;
    let starts: Vec<Vec3> = query
        .selection
        .iter()
        .map(|&v| mesh.positions()[v as usize])
        .collect();
    let (moving, _) = moving_vertices(mesh, query.selection, &starts, 0);
    let mut moved = vec![0u32; mesh.vertex_count()];
    for (i, entry) in moving.iter().enumerate() {
        let v = entry.vertex as usize;
        if query.current[v] != Vec3::from_array(entry.start) {
            moved[v] = i as u32 + 1;
        }
    }
    (moving, moved)
}

/// The parameters of `query`'s filter.
pub fn backstop_query_params(
    query: &BackstopQuery<'_>,
    vertex_rows_base: u32,
    table_size: u32,
) -> BackstopParams {
    let positions = query.mesh.positions();
    let starts: Vec<Vec3> = query
        .selection
        .iter()
        .map(|&v| positions[v as usize])
        .collect();
    let ends: Vec<Vec3> = query
        .selection
        .iter()
        .map(|&v| query.current[v as usize])
        .collect();
    let moved_edge = moved_edge_bound(query.mesh, query.selection, &starts, &ends);
    backstop_params(
        (query.max_edge, moved_edge),
        (0.0, crate::geom::largest_move(&starts, &ends)),
        (1.0 / query.cell_size, table_size),
        query.selection.len(),
        vertex_rows_base,
        query.capacity,
    )
}

/// Builds the hash table of the step's start positions and runs the filter on the GPU.
pub fn run_backstop_filter(
    gpu: &GpuContext,
    query: &BackstopQuery<'_>,
) -> Result<UndecidedPairs, GpuError> {
    let mesh = query.mesh;
    assert_eq!(
        query.current.len(),
        mesh.vertex_count(),
        "one position per vertex"
    );
    let (moving, moved) = backstop_inputs(query);
    let topology = PackedTopology::of(mesh);
    let table_size = table_size_for(mesh.vertex_count());
    let params = backstop_query_params(query, topology.layout.vertex_rows_base, table_size);
    let hashed = super::VertexBuffers::upload(
        gpu,
        mesh.positions(),
        mesh.vertex_layers(),
        &mesh.flags().iter().map(|f| f.bits()).collect::<Vec<_>>(),
    )?;
    let current = gpu.storage_buffer("current positions", query.current, false);
    let topology = topology.upload(gpu)?;
    let moving = gpu.storage_buffer("moving", &moving, false);
    let moved = gpu.storage_buffer("moved", &moved, false);
    let pairs = gpu.output_buffer::<[u32; 2]>("pairs", query.capacity);
    let pair_count = gpu.output_buffer::<u32>("pair count", 1);
    let mut encoder = gpu.encoder("backstop filter");
    let table = super::GpuHashTable::record(
        gpu,
        &mut encoder,
        &hashed.positions,
        &hashed.flags,
        mesh.vertex_count(),
        params.inv_cell_size,
        table_size,
    )?;
    encoder.clear_buffer(&pair_count, 0, None);
    record_backstop_filter(
        gpu,
        &mut encoder,
        &BackstopBuffers {
            positions: &current,
            offsets: &table.offsets,
            entries: &table.entries,
            topology: &topology,
            moving: &moving,
            moved: &moved,
            // No overlay: unread.
            overlay_marks: &moved,
            overlay_offsets: &moved,
            overlay_entries: &moved,
        },
        &params,
        (&pairs, &pair_count),
    )?;
    gpu.submit(encoder);
    let count = gpu.read_buffer::<u32>(&pair_count, 1)?[0];
    let kept = (count as usize).min(query.capacity);
    let pairs = gpu.read_buffer::<[u32; 2]>(&pairs, kept)?;
    Ok(UndecidedPairs { pairs, count })
}
