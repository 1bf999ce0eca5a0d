//! `vertex_normals` and `moved_normals` against their mirrors and the mesh's own normals, with
//! the topology whole and paged.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::common::{
    Binding, SIZES, bumpy_sheets, gpu_for_normals, half_moved_list, normal_params, packed,
    shuffled, worst_relative,
};

/// Normals may differ by this much (unit vectors): the GPU may fuse the cross products'
/// multiply-adds.
const NORMAL_TOLERANCE: f32 = 1e-6;

#[test]
fn vertex_normals_match_cpu_mirror_and_the_mesh() {
    check_vertex_normals(Binding::Whole);
}

#[test]
fn vertex_normals_read_a_topology_split_over_several_bindings() {
    check_vertex_normals(Binding::Paged);
}

fn check_vertex_normals(binding: Binding) {
    // Bumpy sheets (boundaries included) with their positions moved after the normals were
    // last computed; a seeded shuffle of the vertices at awkward sizes, the largest folded
    // into two dimensions. The mirror against `Mesh::recompute_normals_at`, the GPU against
    // the mirror; unlisted normals must stay as they were.
    let mut mesh = bumpy_sheets();
    let mut gpu = gpu_for_normals(binding, &mesh);
    let mut rng = ChaCha8Rng::seed_from_u64(600);
    for p in mesh.positions_mut() {
        p.z += rng.random_range(-0.01..0.01);
    }
    let order = shuffled((0..mesh.vertex_count() as u32).collect(), 601);
    let topology = slayer::gpu::PackedTopology::of(&mesh);
    let flat = packed(mesh.positions());
    let mut worst = 0.0f32;
    for (k, &size) in SIZES.iter().enumerate() {
        if k + 1 == SIZES.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let listed = &order[..size];
        let mut reference = mesh.clone();
        reference.recompute_normals_at(listed);
        let mut mirror = packed(mesh.normals());
        let params = normal_params(size, &topology);
        slayer::cpu::vertex_normals(&params, &flat, &topology.words, listed, &mut mirror);
        let mirror: Vec<Vec3> = mirror.chunks(3).map(Vec3::from_slice).collect();
        assert_eq!(mirror, reference.normals(), "mirror at size {size}");
        let actual = slayer::gpu::run_vertex_normals(&gpu, &mesh, listed).expect("GPU run");
        let off = worst_relative(&actual, &mirror, 1.0);
        assert!(
            off <= NORMAL_TOLERANCE,
            "GPU off the mirror by {off:e} at size {size}"
        );
        worst = worst.max(off);
    }
    eprintln!("vertex_normals: largest deviation GPU vs mirror {worst:e}");
}

#[test]
fn moved_normals_match_cpu_mirror_and_the_mesh() {
    check_moved_normals(Binding::Whole);
}

#[test]
fn moved_normals_read_a_topology_split_over_several_bindings() {
    check_moved_normals(Binding::Paged);
}

fn check_moved_normals(binding: Binding) {
    // Moving lists over a seeded shuffle of the bumpy sheets' vertices at awkward sizes (the
    // largest folded into two dimensions): about half the entries moved off their start, one
    // slot in seven vacant. The mirror against `Mesh::recompute_normals_at` of every corner of
    // the faces around the moved vertices; the GPU against the mirror; every other normal must
    // stay as it was (stale, here).
    let start = bumpy_sheets();
    let mut gpu = gpu_for_normals(binding, &start);
    let order = shuffled((0..start.vertex_count() as u32).collect(), 602);
    let topology = slayer::gpu::PackedTopology::of(&start);
    let mut rng = ChaCha8Rng::seed_from_u64(603);
    let mut worst = 0.0f32;
    let mut refreshed_any = false;
    for (k, &size) in SIZES.iter().enumerate() {
        if k + 1 == SIZES.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let mut mesh = start.clone();
        // Vacant slots move too: their vertex's normals must stay all the same.
        let (moving, moved) = half_moved_list(
            start.positions(),
            mesh.positions_mut(),
            &order[..size],
            (&mut rng, |rng| {
                Vec3::new(0.0, 0.0, rng.random_range(-0.01..0.01))
            }),
        );
        let mut corners: Vec<u32> = moved
            .iter()
            .flat_map(|&v| mesh.faces_around(v).flat_map(|f| mesh.faces()[f as usize]))
            .collect();
        corners.sort_unstable();
        corners.dedup();
        refreshed_any |= !corners.is_empty();
        let mut reference = mesh.clone();
        reference.recompute_normals_at(&corners);
        let flat = packed(mesh.positions());
        let mut mirror = packed(mesh.normals());
        let params = normal_params(size, &topology);
        slayer::cpu::moved_normals(&params, &flat, &topology.words, &moving, &mut mirror);
        let mirror: Vec<Vec3> = mirror.chunks(3).map(Vec3::from_slice).collect();
        assert_eq!(mirror, reference.normals(), "mirror at size {size}");
        let actual = slayer::gpu::run_moved_normals(&gpu, &mesh, &moving).expect("GPU run");
        let off = worst_relative(&actual, &mirror, 1.0);
        assert!(
            off <= NORMAL_TOLERANCE,
            "GPU off the mirror by {off:e} at size {size}"
        );
        for (v, (a, m)) in actual.iter().zip(&mirror).enumerate() {
            if corners.binary_search(&(v as u32)).is_err() {
                assert_eq!(a, m, "normal of vertex {v} changed at size {size}");
            }
        }
        worst = worst.max(off);
    }
    assert!(refreshed_any);
    eprintln!("moved_normals: largest deviation GPU vs mirror {worst:e}");
}
