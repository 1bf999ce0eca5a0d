// First pass of the spatial-hash build (docs/design.md, "Data"): the hash-table slot of every vertex's cell.
// CPU mirror: src/cpu/cell_keys.rs.

#import shared/grid

struct CellKeyParams {
    count: u32,
    table_mask: u32,
    inv_cell_size: f32,
    _pad: u32,
}

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: CellKeyParams;
// Positions packed as x, y, z triples (12 bytes a vertex, as on the CPU).
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read_write> keys: array<u32>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i >= params.count {
        return;
    }
    let p = vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
    keys[i] = hash_cell(cell_of(p, params.inv_cell_size), params.table_mask);
}
