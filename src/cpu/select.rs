//! Mirror of `wgsl/select.wgsl`. Run in order, the append atomic lists the selection cell by
//! cell (x fastest) and, within a cell, in bucket order; the GPU's order is arbitrary, so only
//! the set of (vertex, weight) pairs is comparable.

use glam::{IVec3, UVec3, Vec3};

use super::shared::falloff_weight;
use crate::gpu::{SelectParams, SelectedVertex};
use crate::grid::{cell_coordinates, hash_cell};
use crate::mesh::VertexFlags;

const WORKGROUP_SIZE: u32 = 64;

/// The per-vertex inputs and the hash table the kernel binds.
pub struct SelectInputs<'a> {
    /// Packed x, y, z triples.
    pub positions: &'a [f32],
    pub vertex_layers: &'a [u32],
    pub flags: &'a [u32],
    pub active_layers: &'a [u32],
    pub offsets: &'a [u32],
    pub entries: &'a [u32],
}

fn position(inputs: &SelectInputs<'_>, v: u32) -> Vec3 {
    let i = 3 * v as usize;
    Vec3::new(
        inputs.positions[i],
        inputs.positions[i + 1],
        inputs.positions[i + 2],
    )
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
    let offset = position(inputs, v) - Vec3::from_array(params.center);
    let distance_squared = offset.dot(offset);
    if distance_squared > params.radius * params.radius {
        return;
    }
    let weight = falloff_weight(
        params.falloff,
        params.blend_n,
        distance_squared.sqrt() / params.radius,
    );
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
    let workgroups = params.candidate_count.div_ceil(WORKGROUP_SIZE);
    for workgroup in 0..workgroups {
        for local in 0..WORKGROUP_SIZE {
            let candidate = workgroup * WORKGROUP_SIZE + local;
            if candidate >= params.candidate_count {
                continue;
            }
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
                if cell_coordinates(position(inputs, v), params.inv_cell_size) == cell {
                    consider(params, inputs, v, selected, selection_count);
                }
            }
        }
    }
}
