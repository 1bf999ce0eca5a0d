// Files a step's moved vertices in the overlay where they now are, so that the next sample of a
// stroke recorded in the same submission finds them there without growing its reach (the host's
// `Hashed::refile`, on the GPU). One invocation per slot of the moving list: an entry whose
// vertex is away from its start records its position as where it is filed and, when the overlay
// does not hold it yet, takes the next free slot. Vacant slots and still vertices do nothing.
// A vertex appears once in a moving list, so no two invocations write the same mark.
// The table itself is rebuilt from the slots after (`overlay_keys`).
// CPU mirror: src/cpu/overlay_members.rs.

#import shared/grid
#import shared/mesh
#import shared/moves
#import shared/overlay

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: OverlayParams;
// Positions after the step, packed x, y, z.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> moving: array<MovingVertex>;
// Per vertex: its slot + 1 when the overlay holds it.
@group(0) @binding(3) var<storage, read_write> marks: array<u32>;
@group(0) @binding(4) var<storage, read_write> members: array<u32>;
@group(0) @binding(5) var<storage, read_write> member_count: atomic<u32>;
// Per vertex, packed x, y, z: the position it is filed at (what `select` reads as `hashed`).
@group(0) @binding(6) var<storage, read_write> filed_at: array<f32>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i >= params.count {
        return;
    }
    let entry = moving[i];
    if entry.vertex == INVALID {
        return;
    }
    let v = entry.vertex;
    let p = vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
    if all(p == entry.start) {
        return;
    }
    if marks[v] == 0u {
        let slot = atomicAdd(&member_count, 1u);
        // The host gives the list room for every slot a submission can take; past it the
        // vertex would stay unfiled, so it is left unmoved in the filing too.
        if slot >= params.room {
            return;
        }
        members[slot] = v;
        marks[v] = slot + 1u;
    }
    filed_at[3u * v] = p.x;
    filed_at[3u * v + 1u] = p.y;
    filed_at[3u * v + 2u] = p.z;
}
