// The longest move of a sample: the largest distance from a selected vertex's position to its
// brush target, accumulated as f32 bits in the run's gate status (shared/gate), which
// `sample_gate` compares with the move the sample's passes were sized for. The host's
// `pipeline::step::longest_move` over the same selection gives the same value up to the
// rounding of `distance`; the host checks its own again when it takes the sample.
// One invocation per slot of the selection list up to `capacity`.
// CPU mirror: src/cpu/longest_move.rs.

#import shared/brush
#import shared/gate
#import shared/grid

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: GateParams;
// Packed x, y, z per vertex: the sample's start positions.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> selected: array<SelectedVertex>;
@group(0) @binding(3) var<storage, read> selection_count: u32;
// Packed x, y, z per selection entry, as `deform` wrote them.
@group(0) @binding(4) var<storage, read> targets: array<f32>;
@group(0) @binding(5) var<storage, read_write> status: GateStatus;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i >= min(selection_count, params.capacity) {
        return;
    }
    let v = selected[i].vertex;
    let p = vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
    let q = vec3<f32>(targets[3u * i], targets[3u * i + 1u], targets[3u * i + 2u]);
    // Non-negative (or NaN): its bits order as the distances do.
    atomicMax(&status.longest, bitcast<u32>(distance(p, q)));
}
