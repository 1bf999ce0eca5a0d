//! Host side of `wgsl/vertex_normals.wgsl` (the normals of listed vertices) and of
//! `wgsl/moved_normals.wgsl` (those a step's moves changed, found from its moving list):
//! normals recomputed on the GPU so that a stroke's next sample, recorded in the same
//! submission, needs nothing from the CPU.

use glam::Vec3;

use super::{GpuContext, GpuError, PackedTopology, Workgroups};
use crate::abi::{MovingVertex, NormalParams, WORKGROUP_SIZE};
use crate::mesh::Mesh;

/// Records the pass rewriting the normals (packed x, y, z per vertex) of the first `count`
/// entries of `vertices`, from `positions` and the packed topology (paged).
#[allow(clippy::too_many_arguments)]
pub fn record_vertex_normals(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    positions: &wgpu::Buffer,
    topology: &wgpu::Buffer,
    vertex_rows_base: u32,
    vertices: &wgpu::Buffer,
    count: usize,
    normals: &wgpu::Buffer,
) -> Result<(), GpuError> {
    let params = NormalParams {
        count: count as u32,
        vertex_rows_base,
        _pad0: 0,
        _pad1: 0,
    };
    let pipeline = gpu.compute_pipeline("vertex_normals")?;
    let uniform = gpu.uniform_buffer("vertex_normals params", &params);
    gpu.record_paged_dispatch(
        encoder,
        &pipeline,
        "vertex_normals",
        &[&uniform, positions, vertices, normals],
        &[topology],
        Workgroups::Cover {
            invocations: count,
            workgroup_size: WORKGROUP_SIZE,
        },
    );
    Ok(())
}

/// `mesh`'s normals with those of `vertices` recomputed on the GPU.
pub fn run_vertex_normals(
    gpu: &GpuContext,
    mesh: &Mesh,
    vertices: &[u32],
) -> Result<Vec<Vec3>, GpuError> {
    gpu.check_binding::<Vec3>("vertex positions", mesh.vertex_count())?;
    let topology = PackedTopology::of(mesh);
    let positions = gpu.storage_buffer("positions", mesh.positions(), false);
    let topology_buffer = topology.upload(gpu)?;
    let listed = gpu.storage_buffer("listed vertices", vertices, false);
    let normals = gpu.storage_buffer("normals", mesh.normals(), true);
    let mut encoder = gpu.encoder("vertex_normals");
    record_vertex_normals(
        gpu,
        &mut encoder,
        &positions,
        &topology_buffer,
        topology.layout.vertex_rows_base,
        &listed,
        vertices.len(),
        &normals,
    )?;
    gpu.submit(encoder);
    gpu.read_buffer(&normals, mesh.vertex_count())
}

/// Records the pass rewriting the normals around the entries of the first `slots` slots of
/// `moving` that are away from their start in `positions`.
pub fn record_moved_normals(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (positions, topology): (&wgpu::Buffer, &wgpu::Buffer),
    vertex_rows_base: u32,
    (moving, slots): (&wgpu::Buffer, usize),
    normals: &wgpu::Buffer,
) -> Result<(), GpuError> {
    let pass = MovedPass {
        kernel: "moved_normals",
        positions,
        topology,
        vertex_rows_base,
    };
    pass.record(gpu, encoder, (moving, slots), normals)
}

/// `mesh`'s normals with those around the moved entries of `moving` recomputed on the GPU
/// (an entry moved when `mesh` has its vertex away from the entry's start).
pub fn run_moved_normals(
    gpu: &GpuContext,
    mesh: &Mesh,
    moving: &[MovingVertex],
) -> Result<Vec<Vec3>, GpuError> {
    MovedPass::run(gpu, "moved_normals", mesh, moving, mesh.normals())
}

/// A kernel over a step's moving list that visits the faces around each entry whose vertex
/// moved (`moved_normals`, `moved_edges`): they bind alike — `NormalParams`, the positions, the
/// list, one output, the packed topology paged — and run one invocation per slot.
pub(super) struct MovedPass<'a> {
    pub kernel: &'static str,
    pub positions: &'a wgpu::Buffer,
    pub topology: &'a wgpu::Buffer,
    pub vertex_rows_base: u32,
}

impl MovedPass<'_> {
    /// Records the kernel over the first `slots` slots of `moving`, writing `output`.
    pub fn record(
        &self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        (moving, slots): (&wgpu::Buffer, usize),
        output: &wgpu::Buffer,
    ) -> Result<(), GpuError> {
        let params = NormalParams {
            count: slots as u32,
            vertex_rows_base: self.vertex_rows_base,
            _pad0: 0,
            _pad1: 0,
        };
        let pipeline = gpu.compute_pipeline(self.kernel)?;
        let uniform = gpu.uniform_buffer(&format!("{} params", self.kernel), &params);
        gpu.record_paged_dispatch(
            encoder,
            &pipeline,
            self.kernel,
            &[&uniform, self.positions, moving, output],
            &[self.topology],
            Workgroups::Cover {
                invocations: slots,
                workgroup_size: WORKGROUP_SIZE,
            },
        );
        Ok(())
    }

    /// Runs `kernel` over `moving` on `mesh` (its positions being where the entries are now),
    /// its output starting as `output`, and reads the output back.
    pub fn run<T: bytemuck::Pod>(
        gpu: &GpuContext,
        kernel: &'static str,
        mesh: &Mesh,
        moving: &[MovingVertex],
        output: &[T],
    ) -> Result<Vec<T>, GpuError> {
        gpu.check_binding::<Vec3>("vertex positions", mesh.vertex_count())?;
        let topology = PackedTopology::of(mesh);
        let positions = gpu.storage_buffer("positions", mesh.positions(), false);
        let topology_buffer = topology.upload(gpu)?;
        let moving_buffer = gpu.storage_buffer("moving list", moving, false);
        let output_buffer = gpu.storage_buffer(kernel, output, true);
        let pass = MovedPass {
            kernel,
            positions: &positions,
            topology: &topology_buffer,
            vertex_rows_base: topology.layout.vertex_rows_base,
        };
        let mut encoder = gpu.encoder(kernel);
        pass.record(
            gpu,
            &mut encoder,
            (&moving_buffer, moving.len()),
            &output_buffer,
        )?;
        gpu.submit(encoder);
        gpu.read_buffer(&output_buffer, output.len())
    }
}
