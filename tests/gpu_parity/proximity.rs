//! One proximity pass against its mirror and the CPU pipeline's `pull_back`, with the topology
//! whole and paged.

use glam::Vec3;
use slayer::gpu::table_size_for;
use slayer::grid::SpatialHash;

use crate::common::{
    Binding, ProximityScene, binding_limit_paging, folded_sheet, gathered_region, gpu,
    gpu_with_binding_limit, host_moving_list, mesh_table, packed, pressed_sheets,
    proximity_tolerance,
};

/// The proximity mirror's verdicts for `selection` of `scene`, with `current` positions.
fn cpu_proximity(
    scene: &ProximityScene,
    query: &slayer::gpu::ProximityQuery<'_>,
) -> Vec<slayer::gpu::PulledVertex> {
    let mesh = &scene.mesh;
    let (moving, rings) = host_moving_list(mesh, query.selection, query.ring);
    let topology = slayer::gpu::PackedTopology::of(mesh);
    let table_size = table_size_for(mesh.vertex_count());
    let params = slayer::gpu::proximity_params(query, topology.layout.vertex_rows_base, table_size);
    let table = mesh_table(mesh, params.inv_cell_size, table_size);
    let flat = packed(query.current);
    let mut pulls = vec![0u32; query.selection.len()];
    slayer::cpu::proximity(
        &params,
        &slayer::cpu::ProximityInputs {
            positions: &flat,
            offsets: &table.offsets,
            entries: &table.entries,
            topology: &topology.words,
            moving: &moving,
            rings: &rings,
            marks: query.marks.unwrap_or(&[]),
            overlay_marks: &[],
            overlay_offsets: &[],
            overlay_entries: &[],
        },
        &mut pulls,
    );
    slayer::gpu::verdicts(&moving, &flat, &pulls)
}

/// `collide::pull_back` (the CPU backend's first pass) for the same step.
fn reference_pull_back(
    scene: &ProximityScene,
    selection: &[u32],
    distance: f32,
    ring: u32,
) -> Vec<Option<Vec3>> {
    let mesh = &scene.mesh;
    let grid = SpatialHash::build(mesh, scene.edge).unwrap();
    let mut current = mesh.clone();
    for &v in selection {
        current.positions_mut()[v as usize] = scene.targets[v as usize];
    }
    let active = vec![true; mesh.layer_count()];
    let state = slayer::collide::StrokeState {
        grid: Some(&grid),
        active: &active,
        parallel: false,
        collision_distance: distance,
        ring,
        max_edge: mesh.longest_edge().max(current.longest_edge()),
        cull: true,
    };
    let pairs: Vec<(u32, f32)> = selection.iter().map(|&v| (v, 1.0)).collect();
    let targets: Vec<Vec3> = selection
        .iter()
        .map(|&v| scene.targets[v as usize])
        .collect();
    let (region, _) = gathered_region(&state, mesh, &pairs, &targets);
    let mut scratch = slayer::collide::Scratch::default();
    selection
        .iter()
        .map(|&v| {
            let start = mesh.positions()[v as usize];
            if current.positions()[v as usize] == start {
                return None;
            }
            slayer::collide::pull_back(&state, &region, &current, v, start, None, &mut scratch)
        })
        .collect()
}

/// Largest distance between two verdict lists on `scene`, in its edge lengths, after checking
/// their flags agree.
fn compare_pulled(
    label: &str,
    actual: &[slayer::gpu::PulledVertex],
    expected: &[slayer::gpu::PulledVertex],
    scene: &ProximityScene,
) -> f32 {
    let edge = scene.edge;
    assert_eq!(actual.len(), expected.len(), "{label}");
    let mut worst = 0.0f32;
    for (i, (a, e)) in actual.iter().zip(expected).enumerate() {
        assert_eq!(
            a.pulled, e.pulled,
            "{label}: entry {i} pulled {a:?} vs {e:?}"
        );
        let off = Vec3::from_array(a.position).distance(Vec3::from_array(e.position)) / edge;
        worst = worst.max(off);
    }
    assert!(
        worst <= proximity_tolerance(scene),
        "{label}: off by {worst:e} edge lengths"
    );
    worst
}

/// Both Jacobi passes of proximity on `scene` at awkward selection sizes (the largest folds its
/// dispatch into two dimensions): the mirror against `pull_back`, the GPU against the mirror;
/// then a second pass that tests only the faces of the vertices the first pulled back.
fn check_proximity(scene: ProximityScene, binding: Binding) {
    let (distance, ring) = (0.05, 2);
    let (mut worst_mirror, mut worst_gpu) = (0.0f32, 0.0f32);
    let all = scene.order.len();
    let large_odd = if all >= 4001 { 4001 } else { all | 1 };
    let sizes = [0, 1, 63, 64, 65, 1000.min(all), large_odd.min(all)];
    let mut gpu = match binding {
        Binding::Whole => gpu(),
        Binding::Paged => {
            // Whole: positions, the hash table, the largest selection's entries. Paged: the
            // topology and the exclusion rings.
            let largest = &scene.order[..sizes[sizes.len() - 1]];
            let (moving, rings) = host_moving_list(&scene.mesh, largest, ring);
            let vertices = scene.mesh.vertex_count() as u64;
            let unpaged = [
                12 * vertices,
                4 * (table_size_for(scene.mesh.vertex_count()) as u64 + 1),
                std::mem::size_of_val(moving.as_slice()) as u64,
            ];
            let topology = slayer::gpu::PackedTopology::of(&scene.mesh).words.len() as u64 * 4;
            let limit = binding_limit_paging(
                unpaged.into_iter().max().unwrap(),
                &[topology, 4 * rings.len() as u64],
            );
            gpu_with_binding_limit(limit)
        }
    };
    for (k, &size) in sizes.iter().enumerate() {
        let label = format!("{} at size {size}", scene.name);
        gpu.limits.max_compute_workgroups_per_dimension =
            if k + 1 == sizes.len() { 7 } else { 65_535 };
        let selection = &scene.order[..size];
        let mut current = scene.mesh.positions().to_vec();
        for &v in selection {
            current[v as usize] = scene.targets[v as usize];
        }
        let query = slayer::gpu::ProximityQuery {
            mesh: &scene.mesh,
            current: &current,
            selection,
            distance,
            ring,
            max_edge: scene.mesh.longest_edge(),
            cell_size: scene.edge,
            marks: None,
        };
        let mirror = cpu_proximity(&scene, &query);
        let reference: Vec<slayer::gpu::PulledVertex> =
            reference_pull_back(&scene, selection, distance, ring)
                .into_iter()
                .zip(selection)
                .map(|(p, &v)| match p {
                    Some(p) => slayer::gpu::PulledVertex {
                        position: p.to_array(),
                        pulled: 1,
                    },
                    None => slayer::gpu::PulledVertex {
                        position: current[v as usize].to_array(),
                        pulled: 0,
                    },
                })
                .collect();
        worst_mirror = worst_mirror.max(compare_pulled(
            &format!("{label}: mirror vs pull_back"),
            &mirror,
            &reference,
            &scene,
        ));
        let actual = slayer::gpu::run_proximity(&gpu, &query).expect("GPU run");
        worst_gpu = worst_gpu.max(compare_pulled(
            &format!("{label}: GPU vs mirror"),
            &actual,
            &mirror,
            &scene,
        ));
        if size >= 1000 {
            let clamped = mirror.iter().filter(|p| p.pulled == 1).count();
            assert!(clamped * 4 > size, "{label}: only {clamped} clamp");
        }

        // Second pass: the first's results written in, only faces it changed.
        let mut after = current.clone();
        let mut marks = vec![0u32; scene.mesh.vertex_count()];
        for (p, &v) in mirror.iter().zip(selection) {
            after[v as usize] = Vec3::from_array(p.position);
            marks[v as usize] = p.pulled;
        }
        let query = slayer::gpu::ProximityQuery {
            current: &after,
            marks: Some(&marks),
            ..query
        };
        let mirror = cpu_proximity(&scene, &query);
        let actual = slayer::gpu::run_proximity(&gpu, &query).expect("GPU run");
        worst_gpu = worst_gpu.max(compare_pulled(
            &format!("{label}, second pass: GPU vs mirror"),
            &actual,
            &mirror,
            &scene,
        ));
    }
    eprintln!(
        "proximity, {}{}: largest deviation mirror vs pull_back {worst_mirror:e}, GPU vs mirror {worst_gpu:e} (× edge)",
        scene.name,
        if binding == Binding::Paged {
            ", topology paged"
        } else {
            ""
        }
    );
}

#[test]
fn proximity_matches_cpu_mirror_and_the_cpu_pipeline_on_pressed_sheets() {
    check_proximity(pressed_sheets(), Binding::Whole);
}

#[test]
fn proximity_matches_cpu_mirror_and_the_cpu_pipeline_on_a_folded_sheet() {
    check_proximity(folded_sheet(), Binding::Whole);
}

#[test]
fn proximity_reads_a_topology_split_over_several_bindings() {
    check_proximity(pressed_sheets(), Binding::Paged);
}
