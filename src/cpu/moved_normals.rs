//! Mirror of `wgsl/moved_normals.wgsl`: after a step, the normal of every corner of every face
//! around a vertex the step moved, recomputed.

use super::shared::{invocations, packed_position};
use super::vertex_normals::{vertex_normal, write_normal};
use crate::abi::{MovingVertex, NormalParams};
use crate::mesh::INVALID;

/// Over the first `params.count` slots of `moving`: for each entry whose vertex is away from its
/// start in `positions` (packed x, y, z), rewrites in `normals` the normals of the corners of
/// the faces around it.
pub fn moved_normals(
    params: &NormalParams,
    positions: &[f32],
    topology: &[u32],
    moving: &[MovingVertex],
    normals: &mut [f32],
) {
    for i in invocations(params.count) {
        let entry = &moving[i as usize];
        if entry.vertex == INVALID
            || packed_position(positions, entry.vertex).to_array() == entry.start
        {
            continue;
        }
        let row = (params.vertex_rows_base + 2 * entry.vertex) as usize;
        let first = topology[row];
        for k in first..first + topology[row + 1] {
            let f = topology[k as usize] as usize;
            for corner in 0..3 {
                let u = topology[4 * f + corner];
                let n = vertex_normal(positions, topology, params.vertex_rows_base, u);
                write_normal(normals, u, n);
            }
        }
    }
}
