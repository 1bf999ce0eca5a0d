// Last pass of a multi-block exclusive scan: adds each block's offset (the exclusive scan of
// the block sums `scan` wrote) to every value of the block.
// CPU mirror: src/cpu/scan_add.rs.

#import shared/mesh

// Must equal `scan`'s workgroup size: one workgroup here is one block there.
const WORKGROUP_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: CountParams;
@group(0) @binding(1) var<storage, read_write> values: array<u32>;
@group(0) @binding(2) var<storage, read> block_offsets: array<u32>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(local_invocation_id) local_id: vec3<u32>,
    @builtin(workgroup_id) workgroup_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let block = workgroup_id.x + workgroup_id.y * workgroups.x;
    let i = block * WORKGROUP_SIZE + local_id.x;
    if i < params.count {
        values[i] += block_offsets[block];
    }
}
