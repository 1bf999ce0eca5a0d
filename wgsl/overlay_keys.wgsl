// First pass of the overlay's rebuild from its slots (`cell_keys` for the overlay): the bucket
// of each member's cell, from where it is filed, and the flag word `cell_counts` reads — dead
// for the slots past the member count, so that the counting sort over every slot of the room
// files only the members. Dead vertices stay filed, as on the host (queries read the mesh's
// flags and leave them out).
// CPU mirror: src/cpu/overlay_keys.rs.

#import shared/grid
#import shared/mesh
#import shared/overlay

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: OverlayParams;
@group(0) @binding(1) var<storage, read> members: array<u32>;
@group(0) @binding(2) var<storage, read> member_count: u32;
// Per vertex, packed x, y, z: where it is filed.
@group(0) @binding(3) var<storage, read> filed_at: array<f32>;
@group(0) @binding(4) var<storage, read_write> keys: array<u32>;
@group(0) @binding(5) var<storage, read_write> flags: array<u32>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let slot = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if slot >= params.count {
        return;
    }
    if slot >= min(member_count, params.room) {
        flags[slot] = VERTEX_DEAD;
        return;
    }
    let v = members[slot];
    let p = vec3<f32>(filed_at[3u * v], filed_at[3u * v + 1u], filed_at[3u * v + 2u]);
    keys[slot] = hash_cell(cell_of(p, params.inv_cell_size), params.table_mask);
    flags[slot] = 0u;
}
