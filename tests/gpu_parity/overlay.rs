//! The overlay table's kernels (`overlay_members`, `overlay_keys`, `overlay_entries`) against
//! their mirrors and the host's filing.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slayer::gpu::table_size_for;
use slayer::mesh::INVALID;

use crate::common::{SIZES, gpu, half_moved_list, packed, random_positions, shuffled};

/// Overlay slots over `vertex_count` vertices at `filed` (packed): `held` members in slots in
/// the order given, marks slot + 1, room for `room`.
fn overlay_slots(filed: &[Vec3], held: &[u32], room: usize) -> slayer::cpu::OverlaySlots {
    let mut slots = slayer::cpu::OverlaySlots {
        marks: vec![0; filed.len()],
        members: vec![INVALID; room],
        member_count: held.len() as u32,
        filed_at: packed(filed),
    };
    for (slot, &v) in held.iter().enumerate() {
        slots.members[slot] = v;
        slots.marks[v as usize] = slot as u32 + 1;
    }
    slots
}

/// The members of `slots` (sorted), checked against the marks: slot `s` holds `v` exactly
/// when `marks[v]` is `s + 1`, and no other vertex is marked.
fn checked_members(slots: &slayer::cpu::OverlaySlots, room: usize, what: &str) -> Vec<u32> {
    let taken = (slots.member_count as usize).min(room);
    let mut members = slots.members[..taken].to_vec();
    for (s, &v) in members.iter().enumerate() {
        assert_eq!(slots.marks[v as usize], s as u32 + 1, "{what}: mark of {v}");
    }
    let marked = slots.marks.iter().filter(|&&m| m != 0).count();
    assert_eq!(marked, taken, "{what}: marked vertices");
    members.sort_unstable();
    members
}

#[test]
fn overlay_members_file_the_moved_entries_as_the_cpu_mirror_does() {
    // Moving lists over a seeded shuffle of 9000 vertices at awkward sizes (the largest folded
    // into two dimensions), one slot in seven vacant, about half the entries moved; the overlay
    // already holds every eleventh vertex, so some moved entries are members and keep their
    // slot. Slots are handed out in atomic order on the GPU: members compare as sets, marks
    // must name each member's slot, filed positions bit for bit.
    let mut gpu = gpu();
    let vertex_count = 9000;
    let start = random_positions(vertex_count, 910, 3.0);
    let held: Vec<u32> = (0..vertex_count as u32).step_by(11).collect();
    let order = shuffled((0..vertex_count as u32).collect(), 911);
    let mut rng = ChaCha8Rng::seed_from_u64(912);
    for (k, &size) in SIZES.iter().enumerate() {
        if k + 1 == SIZES.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let mut positions = start.clone();
        let (moving, moved) = half_moved_list(
            &start,
            &mut positions,
            &order[..size],
            (&mut rng, |rng| {
                Vec3::new(0.0, 0.0, rng.random_range(0.001..0.3))
            }),
        );
        let room = held.len() + size;
        let before = overlay_slots(&start, &held, room);
        let flat = packed(&positions);
        let params = slayer::gpu::OverlayParams {
            count: size as u32,
            room: room as u32,
            table_mask: 0,
            inv_cell_size: 1.0,
        };
        let mut mirror = before.clone();
        slayer::cpu::overlay_members(&params, &flat, &moving, &mut mirror);
        let actual =
            slayer::gpu::run_overlay_members(&gpu, &positions, &moving, &before).expect("GPU run");
        // What the mirror must do: the held members and every moved entry, filed where it is.
        let mut expected: Vec<u32> = held.iter().chain(&moved).copied().collect();
        expected.sort_unstable();
        expected.dedup();
        let mirror_members = checked_members(&mirror, room, "mirror");
        assert_eq!(mirror_members, expected, "mirror members at size {size}");
        let mut filed = start.clone();
        for &v in &moved {
            filed[v as usize] = positions[v as usize];
        }
        let filed = packed(&filed);
        assert_eq!(
            mirror.filed_at, filed,
            "mirror filed positions at size {size}"
        );
        // The GPU as the mirror, held slots untouched.
        assert_eq!(
            actual.member_count, mirror.member_count,
            "count at size {size}"
        );
        assert_eq!(
            checked_members(&actual, room, "GPU"),
            mirror_members,
            "size {size}"
        );
        assert_eq!(
            &actual.members[..held.len()],
            &held[..],
            "held slots at size {size}"
        );
        assert_eq!(
            actual.filed_at, mirror.filed_at,
            "filed positions at size {size}"
        );
    }
    // A room too small: the count still says how many slots were wanted, the vertices past the
    // room stay unmarked and unfiled, and those within it are consistent.
    let size = 1000;
    let moving: Vec<slayer::gpu::MovingVertex> = order[..size]
        .iter()
        .map(|&v| slayer::gpu::MovingVertex {
            start: (start[v as usize] - Vec3::X).to_array(),
            vertex: v,
            ..Default::default()
        })
        .collect();
    let room = held.len() + 10;
    let before = overlay_slots(&start, &held, room);
    let actual = slayer::gpu::run_overlay_members(&gpu, &start, &moving, &before).expect("GPU run");
    let newly = order[..size]
        .iter()
        .filter(|&&v| before.marks[v as usize] == 0)
        .count();
    assert_eq!(actual.member_count as usize, held.len() + newly);
    assert_eq!(
        checked_members(&actual, room, "GPU, room short").len(),
        room
    );
}

#[test]
fn overlay_tables_rebuilt_from_slots_match_the_cpu_chain_and_the_host_filing() {
    // Members in a shuffled slot order at awkward counts, in rooms with spare slots (dead to
    // the counting sort), filed at positions apart from the vertices' own: `overlay_keys`, the
    // counting sort and `overlay_entries` on the GPU against their mirrors chained
    // (`cpu::overlay_slot_table`), bucket sets identical; the mirror against the host's filing
    // (`gpu::overlay_table`) of the same members at the same positions.
    let mut gpu = gpu();
    let vertex_count = 12000;
    let cell_size = 0.25f32;
    let inv = 1.0 / cell_size;
    let filed = random_positions(vertex_count, 920, 2.0);
    let order = shuffled((0..vertex_count as u32).collect(), 921);
    for (k, &size) in SIZES.iter().enumerate() {
        if k + 1 == SIZES.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let room = size + size / 3 + 1;
        let slots = overlay_slots(&filed, &order[..size], room);
        let table_size = table_size_for(room);
        let params = slayer::gpu::OverlayParams {
            count: room as u32,
            room: room as u32,
            table_mask: table_size - 1,
            inv_cell_size: inv,
        };
        let mirror = slayer::cpu::overlay_slot_table(&params, &slots).canonical();
        let mut members = order[..size].to_vec();
        members.sort_unstable();
        let host = slayer::gpu::overlay_table_sized(&filed, &members, inv, table_size).canonical();
        assert_eq!(mirror, host, "mirror vs host filing at size {size}");
        let actual = slayer::gpu::run_overlay_table(&gpu, &slots, table_size, inv)
            .expect("GPU run")
            .canonical();
        assert_eq!(actual, mirror, "GPU vs mirror at size {size}");
    }
}
