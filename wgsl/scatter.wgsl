// Last pass of the spatial-hash build: files every vertex in its bucket's slice of the CSR
// table, `entries[offsets[key] + rank] = vertex`. Ranks come from `cell_counts`, so this pass
// is a plain permutation; the order within a bucket is the order the counting atomics ran in
// (queries filter by cell and never depend on it).
// CPU mirror: src/cpu/scatter.rs.

#import shared/grid
#import shared/mesh

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: CountParams;
@group(0) @binding(1) var<storage, read> keys: array<u32>;
@group(0) @binding(2) var<storage, read> ranks: array<u32>;
// Exclusive scan of the bucket counts: bucket b holds entries[offsets[b]..offsets[b + 1]].
@group(0) @binding(3) var<storage, read> offsets: array<u32>;
@group(0) @binding(4) var<storage, read_write> entries: array<u32>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i >= params.count {
        return;
    }
    let rank = ranks[i];
    if rank == INVALID {
        return;
    }
    entries[offsets[keys[i]] + rank] = i;
}
