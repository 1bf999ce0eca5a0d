// Exclusive prefix sum of one block of WORKGROUP_SIZE values per workgroup, in place, with the
// block's total written to `block_sums`. The host scans `block_sums` with this same kernel
// (recursively, so any length works) and `scan_add` adds the scanned sums back.
// Hillis–Steele in workgroup memory: log2(256) = 8 rounds; the values are u32 counts, so the
// order of the additions cannot change the result.
// CPU mirror: src/cpu/scan.rs.

#import shared/mesh

const WORKGROUP_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: CountParams;
@group(0) @binding(1) var<storage, read_write> values: array<u32>;
@group(0) @binding(2) var<storage, read_write> block_sums: array<u32>;

var<workgroup> running: array<u32, WORKGROUP_SIZE>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(local_invocation_id) local_id: vec3<u32>,
    @builtin(workgroup_id) workgroup_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    // No early return before the barriers: they must be reached by the whole workgroup.
    let block = workgroup_id.x + workgroup_id.y * workgroups.x;
    let local = local_id.x;
    let i = block * WORKGROUP_SIZE + local;
    var value = 0u;
    if i < params.count {
        value = values[i];
    }
    running[local] = value;
    for (var offset = 1u; offset < WORKGROUP_SIZE; offset <<= 1u) {
        workgroupBarrier();
        var left = 0u;
        if local >= offset {
            left = running[local - offset];
        }
        workgroupBarrier();
        running[local] += left;
    }
    if i < params.count {
        values[i] = running[local] - value;
    }
    // A folded dispatch may run a few workgroups past the last block.
    let blocks = (params.count + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    if local == WORKGROUP_SIZE - 1u && block < blocks {
        block_sums[block] = running[local];
    }
}
