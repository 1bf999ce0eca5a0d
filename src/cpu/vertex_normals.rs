//! Mirror of `wgsl/vertex_normals.wgsl` and of `wgsl/shared/normals.wgsl`:
//! `Mesh::recompute_normals_at` over the packed topology (faces in fan order, so the sums are
//! the CPU's, bit for bit).

use glam::Vec3;

use super::shared::{invocations, packed_position};
use crate::abi::NormalParams;

/// Writes the normal of each of the first `params.count` `vertices` into `normals` (packed
/// x, y, z per mesh vertex).
pub fn vertex_normals(
    params: &NormalParams,
    positions: &[f32],
    topology: &[u32],
    vertices: &[u32],
    normals: &mut [f32],
) {
    for i in invocations(params.count) {
        let v = vertices[i as usize];
        let n = vertex_normal(positions, topology, params.vertex_rows_base, v);
        write_normal(normals, v, n);
    }
}

/// `vertex_normal` of `wgsl/shared/normals.wgsl`: the normalized sum of the cross products of
/// the faces around `v`, +Z where it vanishes or is not finite.
pub fn vertex_normal(positions: &[f32], topology: &[u32], vertex_rows_base: u32, v: u32) -> Vec3 {
    let row = (vertex_rows_base + 2 * v) as usize;
    let first = topology[row];
    let mut sum = Vec3::ZERO;
    for k in first..first + topology[row + 1] {
        let f = topology[k as usize] as usize;
        let a = packed_position(positions, topology[4 * f]);
        let b = packed_position(positions, topology[4 * f + 1]);
        let c = packed_position(positions, topology[4 * f + 2]);
        sum += (b - a).cross(c - a);
    }
    let rcp = 1.0 / sum.dot(sum).sqrt();
    if rcp.is_finite() && rcp > 0.0 {
        sum * rcp
    } else {
        Vec3::Z
    }
}

/// Stores `n` as vertex `v`'s row of a packed x, y, z buffer.
pub(super) fn write_normal(normals: &mut [f32], v: u32, n: Vec3) {
    normals[3 * v as usize..3 * v as usize + 3].copy_from_slice(&n.to_array());
}
