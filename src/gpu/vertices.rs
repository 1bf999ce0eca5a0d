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
        assert!(
            layers.len() == positions.len() && flags.len() == positions.len(),
            "one layer and one flag word per vertex"
        );
        gpu.check_binding::<Vec3>("vertex positions", positions.len())?;
        Ok(VertexBuffers {
            count: positions.len(),
            positions: gpu.storage_buffer("positions", positions, true),
            layers: gpu.storage_buffer("vertex layers", layers, false),
            flags: gpu.storage_buffer("vertex flags", flags, true),
        })
    }
}
