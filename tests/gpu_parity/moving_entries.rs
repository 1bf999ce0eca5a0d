//! `moving_entries` against its mirror and the host's moving list and rings, with the topology
//! whole and paged.

use slayer::gpu::SelectedVertex;
use slayer::mesh::INVALID;

use crate::common::{
    Binding, SIZES, binding_limit_paging, bumpy_sheets, gpu, gpu_with_binding_limit,
    host_moving_list, shuffled,
};

/// The mirror of `moving_entries` over `selected` with `capacity` slots.
fn cpu_moving_entries(
    mesh: &slayer::mesh::Mesh,
    selected: &[SelectedVertex],
    (capacity, ring, ring_stride): (usize, u32, u32),
) -> slayer::gpu::BuiltEntries {
    let topology = slayer::gpu::PackedTopology::of(mesh);
    let params = slayer::gpu::EntryParams {
        ring_stride,
        ..slayer::gpu::entry_params(capacity, ring, topology.layout.vertex_rows_base)
    };
    let mut built = slayer::gpu::BuiltEntries {
        moving: vec![slayer::gpu::MovingVertex::default(); capacity],
        rings: vec![0; capacity * ring_stride as usize],
        overflows: 0,
    };
    slayer::cpu::moving_entries(
        &params,
        &slayer::cpu::EntryInputs {
            positions: bytemuck::cast_slice(mesh.positions()),
            layers: mesh.vertex_layers(),
            selected,
            selection_count: selected.len() as u32,
            topology: &topology.words,
        },
        &mut slayer::cpu::EntryOutputs {
            moving: &mut built.moving,
            rings: &mut built.rings,
            overflows: &mut built.overflows,
        },
    );
    built
}

#[test]
fn moving_entries_match_the_cpu_mirror_and_the_hosts_rings() {
    check_moving_entries(Binding::Whole);
}

#[test]
fn moving_entries_read_a_topology_split_over_several_bindings() {
    check_moving_entries(Binding::Paged);
}

/// `moving_entries` on the GPU equals its mirror word for word, and each entry equals the one
/// the host builds (`moving_vertices`: same start, vertex and layer, the same ring as a set),
/// for the unsorted list of a selection at awkward sizes, with vacant slots past it and with
/// fewer slots than it has; rings of one to four, and rings cut short by too little room.
fn check_moving_entries(binding: Binding) {
    let mesh = bumpy_sheets();
    let all: Vec<u32> = shuffled((0..mesh.vertex_count() as u32).collect(), 91);
    let list: Vec<SelectedVertex> = all
        .iter()
        .map(|&vertex| SelectedVertex {
            vertex,
            weight: 0.5,
        })
        .collect();
    let stride = slayer::gpu::RING_STRIDE;
    let (gpu, sizes) = match binding {
        Binding::Whole => (gpu(), SIZES.to_vec()),
        Binding::Paged => {
            let sizes = vec![0, 1, 65, 1000];
            let topology = slayer::gpu::PackedTopology::of(&mesh).words.len() as u64 * 4;
            let unpaged = (12 * mesh.vertex_count() as u64).max(slayer::gpu::ring_bytes(1037));
            let limit = binding_limit_paging(unpaged, &[topology]);
            (gpu_with_binding_limit(limit), sizes)
        }
    };
    let mut overflowed = 0;
    for &size in &sizes {
        for ring in 1..=4 {
            let selected = &list[..size];
            // Vacant slots past the list; for the largest, fewer slots than entries.
            for capacity in [size + 37, size / 2] {
                for room in [stride, 16] {
                    let label = format!("size {size}, ring {ring}, {capacity} slots of {room}");
                    let how = (capacity, ring, room);
                    let actual = slayer::gpu::run_moving_entries(&gpu, &mesh, selected, how)
                        .expect("GPU run");
                    let mirror = cpu_moving_entries(&mesh, selected, how);
                    assert_eq!(actual, mirror, "{label}: GPU against the mirror");
                    overflowed += (actual.overflows > 0) as usize;
                    if room < stride {
                        continue;
                    }
                    assert_eq!(actual.overflows, 0, "{label}: a ring of {ring} fits");
                    let built = selected.len().min(capacity);
                    let vertices: Vec<u32> = selected[..built].iter().map(|s| s.vertex).collect();
                    let (host, host_rings) = host_moving_list(&mesh, &vertices, ring);
                    for (i, entry) in actual.moving.iter().enumerate() {
                        if i >= built {
                            assert_eq!(entry.vertex, INVALID, "{label}: slot {i} is vacant");
                            assert_eq!(entry.ring_start, entry.ring_end, "{label}: slot {i}");
                            continue;
                        }
                        let expected = &host[i];
                        assert_eq!(
                            (entry.start, entry.vertex, entry.layer),
                            (expected.start, expected.vertex, expected.layer),
                            "{label}: entry {i}"
                        );
                        let mut ring_words = actual.rings
                            [entry.ring_start as usize..entry.ring_end as usize]
                            .to_vec();
                        assert_eq!(ring_words[0], entry.vertex, "{label}: the vertex first");
                        let mut host_ring = host_rings
                            [expected.ring_start as usize..expected.ring_end as usize]
                            .to_vec();
                        ring_words.sort_unstable();
                        host_ring.sort_unstable();
                        assert_eq!(ring_words, host_ring, "{label}: ring of entry {i}");
                    }
                }
            }
        }
    }
    assert!(overflowed > 0, "sixteen words are too few for some ring");
}
