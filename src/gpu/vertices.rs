//! The per-vertex buffers every kernel after the hash build reads: packed positions, layer ids
//! and [`crate::mesh::VertexFlags`] bits, one `u32` each. A GPU backend uploads them once per
//! stroke (or after remeshing) and chains the kernels over them.

use glam::Vec3;

use super::{GpuContext, GpuError};

pub struct VertexBuffers {
    pub count: usize,
    /// x, y, z triples (12 bytes a vertex, as `[Vec3]`).
    pub positions: wgpu::Buffer,
    pub layers: wgpu::Buffer,
    pub flags: wgpu::Buffer,
}

impl VertexBuffers {
    pub fn upload(
        gpu: &GpuContext,
        positions: &[Vec3],
        layers: &[u32],
        flags: &[u32],
    ) -> Result<VertexBuffers, GpuError> {
        VertexBuffers::with_room(gpu, positions, layers, flags, positions.len())
    }

    /// Uploaded with rows for `capacity` vertices, so that vertices added later (remeshing) are
    /// written into place rather than uploaded afresh with everything else.
    pub fn with_room(
        gpu: &GpuContext,
        positions: &[Vec3],
        layers: &[u32],
        flags: &[u32],
        capacity: usize,
    ) -> Result<VertexBuffers, GpuError> {
        assert!(
            layers.len() == positions.len() && flags.len() == positions.len(),
            "one layer and one flag word per vertex"
        );
        let capacity = capacity.max(positions.len());
        gpu.check_binding::<Vec3>("vertex positions", capacity)?;
        Ok(VertexBuffers {
            count: positions.len(),
            positions: gpu.storage_buffer_with_room("positions", positions, capacity),
            layers: gpu.storage_buffer_with_room("vertex layers", layers, capacity),
            flags: gpu.storage_buffer_with_room("vertex flags", flags, capacity),
        })
    }
}
