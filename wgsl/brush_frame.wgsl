// The brush frame's sums over a selection (sLayer Algorithm 2: the dab's normal and plane come
// from the surface under the brush): per entry, weight · normal, weight · (position − centre) /
// radius and the weight, summed in fixed point (shared/fixed.wgsl) so that the total does not
// depend on the order the selection was appended in. Each workgroup sums its entries in
// workgroup memory, then adds its total to `sums` once. `sums` (24 words: 7 sums of three
// words, three spare) must be zero before. `deform` turns the sums into the frame
// (`resolve_frame`); the host reads them back to know the frame too.
// CPU mirror: src/cpu/brush_frame.rs.

#import shared/grid
#import shared/brush
#import shared/fixed

struct FrameParams {
    center: vec3<f32>,
    inv_radius: f32,
    // Entries in `selected`: those past min(count, capacity) are not summed.
    capacity: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

const WORKGROUP_SIZE: u32 = 64u;
// Weight · normal x, y, z; weight · offset x, y, z; weight.
const FRAME_SUMS: u32 = 7u;

@group(0) @binding(0) var<uniform> params: FrameParams;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> selected: array<SelectedVertex>;
@group(0) @binding(4) var<storage, read> selection_count: u32;
@group(0) @binding(5) var<storage, read_write> sums: array<atomic<u32>, 24>;

var<workgroup> partial: array<atomic<u32>, 21>;

// Adds `x` to the fixed-point number in words 3k, 3k + 1, 3k + 2 of `partial`: each word takes
// the carry out of the one below exactly when that addition wrapped it.
fn add_partial(k: u32, x: vec3<u32>) {
    let old_lo = atomicAdd(&partial[3u * k], x.x);
    let carry = select(0u, 1u, old_lo + x.x < old_lo);
    let mid = x.y + carry;
    let old_mid = atomicAdd(&partial[3u * k + 1u], mid);
    let carries = select(0u, 1u, mid < carry) + select(0u, 1u, old_mid + mid < old_mid);
    atomicAdd(&partial[3u * k + 2u], x.z + carries);
}

fn add_total(k: u32, x: vec3<u32>) {
    let old_lo = atomicAdd(&sums[3u * k], x.x);
    let carry = select(0u, 1u, old_lo + x.x < old_lo);
    let mid = x.y + carry;
    let old_mid = atomicAdd(&sums[3u * k + 1u], mid);
    let carries = select(0u, 1u, mid < carry) + select(0u, 1u, old_mid + mid < old_mid);
    atomicAdd(&sums[3u * k + 2u], x.z + carries);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    if local < 3u * FRAME_SUMS {
        atomicStore(&partial[local], 0u);
    }
    workgroupBarrier();
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i < min(selection_count, params.capacity) {
        let entry = selected[i];
        let v = entry.vertex;
        let w = entry.weight;
        let n = vec3<f32>(normals[3u * v], normals[3u * v + 1u], normals[3u * v + 2u]);
        let p = vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
        let offset = (p - params.center) * params.inv_radius;
        add_partial(0u, to_fixed(w * n.x));
        add_partial(1u, to_fixed(w * n.y));
        add_partial(2u, to_fixed(w * n.z));
        add_partial(3u, to_fixed(w * offset.x));
        add_partial(4u, to_fixed(w * offset.y));
        add_partial(5u, to_fixed(w * offset.z));
        add_partial(6u, to_fixed(w));
    }
    workgroupBarrier();
    if local < FRAME_SUMS {
        let total = vec3<u32>(
            atomicLoad(&partial[3u * local]),
            atomicLoad(&partial[3u * local + 1u]),
            atomicLoad(&partial[3u * local + 2u]),
        );
        if any(total != vec3<u32>(0u)) {
            add_total(local, total);
        }
    }
}
