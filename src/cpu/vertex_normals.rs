//! Mirror of `wgsl/vertex_normals.wgsl` and of `wgsl/shared/normals.wgsl`:
//! `Mesh::recompute_normals_at` over the packed topology (the same order-free sums, so the normals
//! are the CPU's, bit for bit).

use glam::Vec3;

use super::shared::{invocations, packed_position};
use crate::abi::NormalParams;
use crate::geom;

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

/// `vertex_normal` of `wgsl/shared/normals.wgsl`: the faces around `v` each seen from `v`,
/// summed order-free and normalized ([`geom::fan_normal`]), +Z where that fails.
pub fn vertex_normal(positions: &[f32], topology: &[u32], vertex_rows_base: u32, v: u32) -> Vec3 {
    let row = (vertex_rows_base + 2 * v) as usize;
    let first = topology[row];
    geom::fan_normal(|| {
        (first..first + topology[row + 1]).map(move |k| {
            let f = topology[k as usize] as usize;
            let face = [topology[4 * f], topology[4 * f + 1], topology[4 * f + 2]];
            geom::corner_cross(face, v, |i| packed_position(positions, i))
        })
    })
}

/// Stores `n` as vertex `v`'s row of a packed x, y, z buffer.
pub(super) fn write_normal(normals: &mut [f32], v: u32, n: Vec3) {
    normals[3 * v as usize..3 * v as usize + 3].copy_from_slice(&n.to_array());
}
