// Second pass of the spatial-hash build (docs/design.md, "Data"): how many vertices each bucket holds, and
// each vertex's rank among them. The rank comes from the atomic, so `scatter` needs no atomics
// and no cursor buffer; the order within a bucket is whatever order the atomics ran in.
// Dead vertices are left out, as `SpatialHash::build` leaves them out.
// CPU mirror: src/cpu/cell_counts.rs.

#import shared/grid
#import shared/mesh

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: CountParams;
@group(0) @binding(1) var<storage, read> keys: array<u32>;
@group(0) @binding(2) var<storage, read> flags: array<u32>;
// One count per bucket, zeroed before the pass (plus one trailing zero the scan turns into
// the total).
@group(0) @binding(3) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> ranks: array<u32>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i >= params.count {
        return;
    }
    if (flags[i] & VERTEX_DEAD) != 0u {
        ranks[i] = INVALID;
        return;
    }
    ranks[i] = atomicAdd(&counts[keys[i]], 1u);
}
