//! Mirror of `wgsl/moving_entries.wgsl`: a step's moving entries and exclusion rings from the
//! selection list, each ring grown breadth first over the packed topology's rows.

use super::shared::{invocations, packed_position};
use crate::abi::{EntryParams, MovingVertex, SelectedVertex};
use crate::mesh::INVALID;

/// What the kernel reads besides its parameters.
pub struct EntryInputs<'a> {
    /// Packed x, y, z per vertex.
    pub positions: &'a [f32],
    pub layers: &'a [u32],
    pub selected: &'a [SelectedVertex],
    pub selection_count: u32,
    /// Packed topology words (the GPU path's `PackedTopology`).
    pub topology: &'a [u32],
}

/// What the kernel writes: `capacity` entries, `ring_stride` ring words per entry, and the
/// number of rings cut short.
pub struct EntryOutputs<'a> {
    pub moving: &'a mut [MovingVertex],
    pub rings: &'a mut [u32],
    pub overflows: &'a mut u32,
}

pub fn moving_entries(params: &EntryParams, inputs: &EntryInputs<'_>, out: &mut EntryOutputs<'_>) {
    let topology = |i: u32| inputs.topology[i as usize];
    for i in invocations(params.capacity) {
        let base = i * params.ring_stride;
        if i >= inputs.selection_count {
            out.moving[i as usize] = MovingVertex {
                start: [0.0; 3],
                vertex: INVALID,
                layer: 0,
                ring_start: base,
                ring_end: base,
                _pad: 0,
            };
            continue;
        }
        let v = inputs.selected[i as usize].vertex;
        let rings = &mut out.rings;
        rings[base as usize] = v;
        let mut len = 1u32;
        let mut cut = false;
        let (mut previous, mut layer) = (0u32, 0u32);
        for _ in 0..params.ring {
            let frontier_end = len;
            for j in layer..frontier_end {
                let row = params.vertex_rows_base + 2 * rings[(base + j) as usize];
                let first = topology(row);
                let last = first + topology(row + 1);
                for q in first..last {
                    let f = topology(q);
                    for corner in 0..3 {
                        let w = topology(4 * f + corner);
                        let known = (previous..len).any(|m| rings[(base + m) as usize] == w);
                        if !known {
                            if len < params.ring_stride {
                                rings[(base + len) as usize] = w;
                                len += 1;
                            } else {
                                cut = true;
                            }
                        }
                    }
                }
            }
            previous = layer;
            layer = frontier_end;
        }
        if cut {
            *out.overflows += 1;
        }
        out.moving[i as usize] = MovingVertex {
            start: packed_position(inputs.positions, v).to_array(),
            vertex: v,
            layer: inputs.layers[v as usize],
            ring_start: base,
            ring_end: base + len,
            _pad: 0,
        };
    }
}
