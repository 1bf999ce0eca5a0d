//! Mirror of `wgsl/moved_edges.wgsl`: the run's edge bound grown by the faces around the
//! vertices a sample moved.

use super::shared::{invocations, packed_position};
use crate::abi::{GateStatus, MovingVertex, NormalParams};
use crate::mesh::INVALID;

/// Over the first `params.count` slots of `moving`: for each entry whose vertex is away from
/// its start in `positions` (packed x, y, z), the longest edge of the faces around it, read
/// from the packed `topology` as the kernel reads it, folded into `status.edge` as bits.
pub fn moved_edges(
    params: &NormalParams,
    (positions, topology): (&[f32], &[u32]),
    moving: &[MovingVertex],
    status: &mut GateStatus,
) {
    for i in invocations(params.count) {
        let entry = &moving[i as usize];
        if entry.vertex == INVALID
            || packed_position(positions, entry.vertex).to_array() == entry.start
        {
            continue;
        }
        let row = (params.vertex_rows_base + 2 * entry.vertex) as usize;
        let first = topology[row] as usize;
        let last = first + topology[row + 1] as usize;
        let mut longest = 0.0f32;
        for &f in &topology[first..last] {
            let corner = |k: u32| packed_position(positions, topology[(4 * f + k) as usize]);
            let (a, b, c) = (corner(0), corner(1), corner(2));
            longest = longest.max(a.distance(b).max(b.distance(c)).max(c.distance(a)));
        }
        status.edge = status.edge.max(longest.to_bits());
    }
}
