//! `brush_frame`'s fixed-point sums against its mirror, bit for bit in any order.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slayer::gpu::SelectedVertex;

use crate::common::{SIZES, bumpy_sheets, gpu, selection_under};

#[test]
fn brush_frame_sums_match_the_cpu_mirror_bit_for_bit_in_any_order() {
    // The sums are integers: the GPU's (workgroup partials, then atomics in whatever order the
    // workgroups ran) equal the mirror's exactly, for every awkward size and for the list in
    // any order. The frame they give is the weighted mean normal and centroid (checked in f64).
    let mesh = bumpy_sheets();
    let mut gpu = gpu();
    let (center, radius) = (Vec3::new(3.0, 2.5, 0.1), 2.4);
    let mut full = selection_under(&mesh, center, radius);
    assert!(full.len() > 8315, "selects {}", full.len());
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    for (round, &size) in SIZES.iter().chain(&[full.len()]).enumerate() {
        if round == SIZES.len() {
            // The whole list, its dispatch folded into two dimensions.
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let selection = &mut full[..size];
        let mut mirror = [0u32; slayer::cpu::FRAME_SUM_WORDS];
        let params = slayer::abi::frame_params(center, radius, size);
        fn inputs<'a>(
            mesh: &'a slayer::mesh::Mesh,
            selected: &'a [SelectedVertex],
        ) -> slayer::cpu::FrameInputs<'a> {
            slayer::cpu::FrameInputs {
                positions: mesh.positions(),
                normals: mesh.normals(),
                selected,
                selection_count: selected.len() as u32,
            }
        }
        slayer::cpu::brush_frame(&params, &inputs(&mesh, selection), &mut mirror);
        let on_gpu = |selection: &[SelectedVertex]| {
            slayer::gpu::run_brush_frame(
                &gpu,
                (mesh.positions(), mesh.normals()),
                selection,
                center,
                radius,
            )
            .expect("GPU run")
        };
        assert_eq!(on_gpu(selection), mirror, "size {size}: GPU vs mirror");
        // Shuffled: the same bits on both.
        for i in (1..selection.len()).rev() {
            selection.swap(i, rng.random_range(0..=i));
        }
        let mut shuffled = [0u32; slayer::cpu::FRAME_SUM_WORDS];
        slayer::cpu::brush_frame(&params, &inputs(&mesh, selection), &mut shuffled);
        assert_eq!(shuffled, mirror, "size {size}: mirror in another order");
        assert_eq!(
            on_gpu(selection),
            mirror,
            "size {size}: GPU in another order"
        );
        selection.sort_unstable_by_key(|s| s.vertex);

        let flags = slayer::cpu::FRAME_NORMAL_FROM_SUMS | slayer::cpu::FRAME_PLANE_FROM_SUMS;
        let (normal, plane) =
            slayer::cpu::frame_from_sums(&mirror, flags, (center, radius), (Vec3::Z, center));
        let (mut n, mut p, mut w) = (glam::DVec3::ZERO, glam::DVec3::ZERO, 0.0f64);
        for s in selection.iter() {
            let weight = s.weight as f64;
            n += mesh.normals()[s.vertex as usize].as_dvec3() * weight;
            p += mesh.positions()[s.vertex as usize].as_dvec3() * weight;
            w += weight;
        }
        let (expected_normal, expected_plane) = if w > 0.0 {
            (n.normalize().as_vec3(), (p / w).as_vec3())
        } else {
            (Vec3::Z, center)
        };
        assert!(
            normal.distance(expected_normal) < 1e-5
                && plane.distance(expected_plane) < 1e-5 * radius,
            "size {size}: frame {normal} {plane}, expected {expected_normal} {expected_plane}"
        );
    }
}
