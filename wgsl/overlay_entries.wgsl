// Last pass of the overlay's rebuild: `scatter` filed slots; queries read vertex ids, so each
// filed entry becomes its slot's member. The table's last offset is the number filed.
// CPU mirror: src/cpu/overlay_entries.rs.

#import shared/grid
#import shared/overlay

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: OverlayParams;
@group(0) @binding(1) var<storage, read> members: array<u32>;
// `table_mask + 2` bucket starts.
@group(0) @binding(2) var<storage, read> offsets: array<u32>;
@group(0) @binding(3) var<storage, read_write> entries: array<u32>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let j = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if j >= params.count || j >= offsets[params.table_mask + 1u] {
        return;
    }
    entries[j] = members[entries[j]];
}
