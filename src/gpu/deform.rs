//! Host side of `wgsl/deform.wgsl`: target positions of the selected vertices under one dab.

use glam::Vec3;

use super::{DeformParams, GpuContext, GpuError, SelectedVertex, Workgroups};
use crate::brush::{BrushKind, Dab};
use crate::mesh::{INVALID, Mesh, next};

const WORKGROUP_SIZE: u32 = 64;

/// The `BRUSH_*` code of `wgsl/shared/brush.wgsl`.
pub fn brush_code(kind: BrushKind) -> u32 {
    match kind {
        BrushKind::Draw => 0,
        BrushKind::Inflate => 1,
        BrushKind::Deflate => 2,
        BrushKind::Grab => 3,
        BrushKind::Smooth => 4,
        BrushKind::Flatten => 5,
        BrushKind::Pinch => 6,
        BrushKind::Crease => 7,
        BrushKind::Twist => 8,
        BrushKind::Paint => 9,
    }
}

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
        _pad: 0,
    }
}

/// Smooth's neighbours as CSR (`offsets` has one entry per vertex plus one): the one-ring in
/// fan order, or on a boundary its two boundary neighbours, so that the GPU's centroid sums in
/// the order the CPU pipeline's `ring_centroid` does. Dead and isolated vertices have none.
pub fn smoothing_neighbours(mesh: &Mesh) -> (Vec<u32>, Vec<u32>) {
    let mut offsets = Vec::with_capacity(mesh.vertex_count() + 1);
    let mut neighbours = Vec::with_capacity(6 * mesh.vertex_count());
    offsets.push(0);
    for v in 0..mesh.vertex_count() as u32 {
        if mesh.adjacency().vertex_corner[v as usize] == INVALID {
            // Dead or isolated: nothing to average, the centroid is the vertex itself.
        } else if mesh.is_boundary_vertex(v) {
            let ring = mesh.neighbours(v);
            neighbours.extend([ring[0], ring[ring.len() - 1]]);
        } else {
            neighbours.extend(
                mesh.adjacency()
                    .corners_around(v)
                    .map(|c| mesh.corner_vertex(next(c))),
            );
        }
        offsets.push(neighbours.len() as u32);
    }
    (offsets, neighbours)
}

/// Buffers `deform` reads besides the vertex buffers and the selection.
pub struct DeformBuffers<'a> {
    pub positions: &'a wgpu::Buffer,
    pub normals: &'a wgpu::Buffer,
    pub selected: &'a wgpu::Buffer,
    /// One `u32`: the selection count (`GpuSelection::count`).
    pub selection_count: &'a wgpu::Buffer,
    pub neighbour_offsets: &'a wgpu::Buffer,
    /// Paged.
    pub neighbours: &'a wgpu::Buffer,
}

/// Records the pass writing `targets` (packed x, y, z per selection entry). It runs one
/// invocation per entry of the selection's capacity; those past the count return at once (an
/// indirect dispatch sized from the count is the GPU backend's next step).
pub fn record_deform(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    inputs: &DeformBuffers<'_>,
    dab: &Dab,
    capacity: usize,
    targets: &wgpu::Buffer,
) -> Result<(), GpuError> {
    let params = deform_params(dab, capacity);
    let pipeline = gpu.compute_pipeline("deform")?;
    let uniform = gpu.uniform_buffer("deform params", &params);
    gpu.record_paged_dispatch(
        encoder,
        &pipeline,
        "deform",
        &[
            &uniform,
            inputs.positions,
            inputs.normals,
            inputs.selected,
            inputs.selection_count,
            inputs.neighbour_offsets,
            targets,
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
    gpu.check_binding::<Vec3>("vertex positions", mesh.vertex_count())?;
    let (offsets, neighbours) = smoothing_neighbours(mesh);
    gpu.check_paged("smoothing neighbours", neighbours.len())?;
    let positions = gpu.storage_buffer("positions", mesh.positions(), false);
    let normals = gpu.storage_buffer("normals", mesh.normals(), false);
    let selected = gpu.storage_buffer("selected", selection, false);
    let count = gpu.storage_buffer("selection count", &[selection.len() as u32], false);
    let offsets = gpu.storage_buffer("neighbour offsets", &offsets, false);
    let neighbours = gpu.storage_buffer("neighbours", &neighbours, false);
    let targets = gpu.output_buffer::<Vec3>("targets", selection.len());
    let mut encoder = gpu.encoder("deform");
    record_deform(
        gpu,
        &mut encoder,
        &DeformBuffers {
            positions: &positions,
            normals: &normals,
            selected: &selected,
            selection_count: &count,
            neighbour_offsets: &offsets,
            neighbours: &neighbours,
        },
        dab,
        selection.len(),
        &targets,
    )?;
    gpu.queue.submit([encoder.finish()]);
    gpu.read_buffer(&targets, selection.len())
}
