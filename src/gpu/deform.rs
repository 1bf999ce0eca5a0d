//! Host side of `wgsl/deform.wgsl`: target positions of the selected vertices under one dab.

use glam::Vec3;

use super::brush_frame::{frame_sums_buffer, record_brush_frame};
use super::reusable::Patches;
use super::rows::SlottedRows;
use super::{GpuContext, GpuError, SelectionBuffers, Workgroups};
use crate::abi::frame_params;
use crate::abi::{
    DeformParams, FRAME_SUM_WORDS, FRAME_WORKGROUP_SIZE, FrameSums, SelectedVertex, WORKGROUP_SIZE,
    brush_code,
};
use crate::brush::Dab;
use crate::mesh::{INVALID, Mesh, next};

pub fn deform_params(dab: &Dab, capacity: usize) -> DeformParams {
    let frame = &dab.frame;
    DeformParams {
        center: frame.center.to_array(),
        radius: dab.brush.radius,
        normal: frame.normal.to_array(),
        strength: dab.brush.strength,
        plane_point: frame.plane_point.to_array(),
        pressure: dab.pressure,
        motion: frame.motion.to_array(),
        share: dab.share,
        kind: brush_code(dab.brush.kind),
        sign: dab.brush.direction(),
        capacity: capacity as u32,
        frame: 0,
    }
}

/// Smooth's neighbours, one row per vertex (`super::rows`): the one-ring in fan order, or on a
/// boundary its two boundary neighbours, so that the GPU's centroid sums in the order the CPU
/// pipeline's `ring_centroid` does. Dead and isolated vertices have none.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SmoothingNeighbours {
    /// Per vertex: (start, length) in `words`; `2 · vertex_capacity` words on the GPU.
    pub rows: SlottedRows,
    pub words: Vec<u32>,
}

impl SmoothingNeighbours {
    /// The table as the GPU holds it: room for `vertex_capacity` vertices.
    pub fn table(&self, vertex_capacity: usize) -> Vec<u32> {
        let mut table = self.rows.table.clone();
        table.resize(2 * vertex_capacity.max(self.rows.row_count()), 0);
        table
    }

    /// Queues the rows of `changed` (ascending; vertices added since must be among them) into
    /// `patches`. `false` when they no longer fit the room (lay them out afresh).
    pub fn patch<'a>(
        rows: &mut SlottedRows,
        mesh: &Mesh,
        changed: &[u32],
        (table, words): (&'a wgpu::Buffer, &'a wgpu::Buffer),
        patches: &mut Patches<'a>,
    ) -> bool {
        let row_of = |v, row: &mut Vec<u32>| neighbour_row(mesh, v, row);
        rows.patch(changed, row_of, ((table, 0), words), patches)
    }
}

/// [`SmoothingNeighbours`] of every vertex of `mesh`, with room for rows of vertices up to
/// `vertex_capacity`.
pub fn smoothing_neighbours(mesh: &Mesh, vertex_capacity: usize) -> SmoothingNeighbours {
    let count = mesh.vertex_count();
    let (rows, words) =
        SlottedRows::build(count, vertex_capacity.saturating_sub(count), 0, |v, row| {
            neighbour_row(mesh, v, row)
        });
    SmoothingNeighbours { rows, words }
}

pub(super) fn neighbour_row(mesh: &Mesh, v: u32, row: &mut Vec<u32>) {
    if mesh.adjacency().vertex_corner[v as usize] == INVALID {
        // Dead or isolated: nothing to average, the centroid is the vertex itself.
    } else if mesh.is_boundary_vertex(v) {
        let ring = mesh.neighbours(v);
        row.extend([ring[0], ring[ring.len() - 1]]);
    } else {
        row.extend(
            mesh.adjacency()
                .corners_around(v)
                .map(|c| mesh.corner_vertex(next(c))),
        );
    }
}

/// What `deform` reads: what `brush_frame` reads, and smoothing's neighbours and the sums.
pub struct DeformBuffers<'a> {
    pub selection: SelectionBuffers<'a>,
    /// Per vertex (start, length) of its row in `neighbours`.
    pub neighbour_rows: &'a wgpu::Buffer,
    /// Paged.
    pub neighbours: &'a wgpu::Buffer,
    /// `brush_frame`'s sums (`super::frame_sums_buffer`), read where `params.frame` asks.
    pub frame_sums: &'a wgpu::Buffer,
}

/// Records the pass writing `targets` (packed x, y, z per selection entry). It runs one
/// invocation per entry of the selection's capacity (`params.capacity`); those past the count
/// return at once.
pub fn record_deform(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    inputs: &DeformBuffers<'_>,
    params: &DeformParams,
    targets: &wgpu::Buffer,
) -> Result<(), GpuError> {
    let capacity = params.capacity as usize;
    let pipeline = gpu.compute_pipeline("deform")?;
    let uniform = gpu.uniform_buffer("deform params", params);
    gpu.record_paged_dispatch(
        encoder,
        &pipeline,
        "deform",
        &[
            &uniform,
            inputs.selection.positions,
            inputs.selection.normals,
            inputs.selection.selected,
            inputs.selection.selection_count,
            inputs.neighbour_rows,
            targets,
            inputs.frame_sums,
        ],
        &[inputs.neighbours],
        Workgroups::Cover {
            invocations: capacity,
            workgroup_size: WORKGROUP_SIZE,
        },
    );
    Ok(())
}

/// Deforms `selection` of `mesh` under `dab` on the GPU; one target per selection entry.
pub fn run_deform(
    gpu: &GpuContext,
    mesh: &Mesh,
    dab: &Dab,
    selection: &[SelectedVertex],
) -> Result<Vec<Vec3>, GpuError> {
    Ok(run_framed_deform(gpu, mesh, dab, selection, 0)?.1)
}

/// [`run_deform`] with the frame parts `frame` names (`crate::abi::FRAME_*`) taken from
/// `brush_frame`'s sums over the selection, in the same submission as the GPU backend runs
/// them; also returns the sums.
pub fn run_framed_deform(
    gpu: &GpuContext,
    mesh: &Mesh,
    dab: &Dab,
    selection: &[SelectedVertex],
    frame: u32,
) -> Result<(FrameSums, Vec<Vec3>), GpuError> {
    gpu.check_binding::<Vec3>("vertex positions", mesh.vertex_count())?;
    let neighbours = smoothing_neighbours(mesh, mesh.vertex_count());
    gpu.check_paged("smoothing neighbours", neighbours.words.len())?;
    let positions = gpu.storage_buffer("positions", mesh.positions(), false);
    let normals = gpu.storage_buffer("normals", mesh.normals(), false);
    let selected = gpu.storage_buffer("selected", selection, false);
    let count = gpu.storage_buffer("selection count", &[selection.len() as u32], false);
    let rows = gpu.storage_buffer("neighbour rows", &neighbours.rows.table, false);
    let neighbours = gpu.storage_buffer("neighbours", &neighbours.words, false);
    let targets = gpu.output_buffer::<Vec3>("targets", selection.len());
    let sums = frame_sums_buffer(gpu);
    let inputs = SelectionBuffers {
        positions: &positions,
        normals: &normals,
        selected: &selected,
        selection_count: &count,
    };
    let mut encoder = gpu.encoder("deform");
    record_brush_frame(
        gpu,
        &mut encoder,
        &inputs,
        &frame_params(dab.frame.center, dab.brush.radius, selection.len()),
        &sums,
        Workgroups::Cover {
            invocations: selection.len(),
            workgroup_size: FRAME_WORKGROUP_SIZE,
        },
    )?;
    record_deform(
        gpu,
        &mut encoder,
        &DeformBuffers {
            selection: inputs,
            neighbour_rows: &rows,
            neighbours: &neighbours,
            frame_sums: &sums,
        },
        &DeformParams {
            frame,
            ..deform_params(dab, selection.len())
        },
        &targets,
    )?;
    gpu.submit(encoder);
    let words = gpu.read_buffer::<u32>(&sums, FRAME_SUM_WORDS)?;
    let targets = gpu.read_buffer(&targets, selection.len())?;
    Ok((words.try_into().expect("the sums' words"), targets))
}
