//! Mirror of `wgsl/select.wgsl`. Run in order, the append atomic lists the selection cell by
//! cell (x fastest) and, within a cell, in bucket order; the GPU's order is arbitrary, so only
//! the set of (vertex, weight) pairs is comparable.

use glam::{IVec3, UVec3, Vec3};

use super::shared::{falloff_weight, invocations, packed_position};
use crate::abi::{SelectParams, SelectedVertex};
use crate::grid::{cell_coordinates, hash_cell};
use crate::mesh::{VertexFlags, partial_mask_factor};

/// The per-vertex inputs and the hash table the kernel binds.
pub struct SelectInputs<'a> {
    /// Packed x, y, z triples.
    pub positions: &'a [f32],
    pub vertex_layers: &'a [u32],
    pub flags: &'a [u32],
    pub active_layers: &'a [u32],
    pub offsets: &'a [u32],
    pub entries: &'a [u32],
    /// The packed positions the table was built from (may be `positions`).
    pub hashed: &'a [f32],
    /// Per vertex: nonzero when filed in the overlay table (read when `skip_marked` is set).
    pub marks: &'a [u32],
}

fn consider(
    params: &SelectParams,
    inputs: &SelectInputs<'_>,
    v: u32,
    selected: &mut [SelectedVertex],
    selection_count: &mut u32,
) {
    if inputs.flags[v as usize] & (VertexFlags::MASKED | VertexFlags::DEAD).bits() != 0 {
        return;
    }
    let layer = inputs.vertex_layers[v as usize];
    if layer >= params.layer_count || inputs.active_layers[layer as usize] == 0 {
        return;
    }
    let offset = packed_position(inputs.positions, v) - Vec3::from_array(params.center);
    let distance_squared = offset.dot(offset);
    if distance_squared > params.radius * params.radius {
        return;
    }
    let mut weight = falloff_weight(
        params.falloff,
        (params.blend_n, params.blend_inner),
        distance_squared.sqrt() / params.radius,
    );
    if let Some(factor) = partial_mask_factor(inputs.flags[v as usize]) {
        weight *= factor;
    }
    if weight <= 0.0 {
        return;
    }
    let slot = *selection_count;
    *selection_count += 1;
    if slot < params.capacity {
        selected[slot as usize] = SelectedVertex { vertex: v, weight };
    }
}

/// Appends the selected vertices to `selected`, counting them in `selection_count`.
pub fn select(
    params: &SelectParams,
    inputs: &SelectInputs<'_>,
    selected: &mut [SelectedVertex],
    selection_count: &mut u32,
) {
    for candidate in invocations(params.candidate_count) {
        if params.scan_vertices != 0 {
            consider(params, inputs, candidate, selected, selection_count);
            continue;
        }
        let span = UVec3::from_array(params.cell_span);
        let step = UVec3::new(
            candidate % span.x,
            (candidate / span.x) % span.y,
            candidate / (span.x * span.y),
        );
        let cell = IVec3::from_array(params.cell_min) + step.as_ivec3();
        let bucket = hash_cell(cell, params.table_mask + 1) as usize;
        for j in inputs.offsets[bucket]..inputs.offsets[bucket + 1] {
            let v = inputs.entries[j as usize];
            let elsewhere = params.skip_marked != 0 && inputs.marks[v as usize] != 0;
            let filed_at = packed_position(inputs.hashed, v);
            if !elsewhere && cell_coordinates(filed_at, params.inv_cell_size) == cell {
                consider(params, inputs, v, selected, selection_count);
            }
        }
    }
}
