//! `apply_moves` against its mirror in every mode, and the whole Jacobi loop of a step on the
//! GPU against the CPU pipeline's `clamp_moves`.

use glam::Vec3;
use slayer::grid::SpatialHash;

use crate::common::{
    ProximityScene, SIZES, assert_close, extent, folded_sheet, gathered_region, gpu, packed,
    pressed_sheets, proximity_tolerance, random_positions, random_u32s, shuffled,
};

/// Random moving entries over distinct vertices of `vertex_count`, with targets, verdicts (about
/// half pulled) and marks, for `apply_moves`.
#[allow(clippy::type_complexity)]
fn random_moves(
    count: usize,
    vertex_count: usize,
    seed: u64,
) -> (Vec<slayer::gpu::MovingVertex>, Vec<Vec3>, Vec<u32>) {
    let vertices = shuffled((0..vertex_count as u32).collect(), seed);
    let starts = random_positions(count, seed + 1, 2.0);
    let targets = random_positions(count, seed + 2, 2.0);
    // About half pulled back, by random amounts (65536 − 65536·t, t in [0, 1)).
    let amounts = random_u32s(count, seed + 3, 65536);
    let coins = random_u32s(count, seed + 4, 2);
    let moving = (0..count)
        .map(|i| slayer::gpu::MovingVertex {
            start: starts[i].to_array(),
            vertex: vertices[i],
            layer: 0,
            ring_start: 0,
            ring_end: 0,
            _pad: 0,
        })
        .collect();
    let pulls = (0..count).map(|i| coins[i] * (amounts[i] + 1)).collect();
    (moving, targets, pulls)
}

#[test]
fn apply_moves_matches_cpu_mirror_in_every_mode() {
    use slayer::gpu::{ApplyMode, ApplyParams, run_apply_moves};
    let gpu = gpu();
    for (i, &count) in SIZES.iter().enumerate() {
        let vertex_count = count + count / 2 + 1;
        let (moving, targets, pulls) = random_moves(count, vertex_count, 900 + i as u64);
        let mut positions = random_positions(vertex_count, 950 + i as u64, 2.0);
        // Every third entry where it started: `MarkMoved` leaves those unmarked.
        for entry in moving.iter().step_by(3) {
            positions[entry.vertex as usize] = Vec3::from_array(entry.start);
        }
        let marks = random_u32s(vertex_count, 960 + i as u64, 2);
        for mode in [
            ApplyMode::Place,
            ApplyMode::Pull,
            ApplyMode::PullLast,
            ApplyMode::Gather,
            ApplyMode::MarkMoved,
            ApplyMode::Clear,
        ] {
            let actual = run_apply_moves(&gpu, mode, &moving, &targets, &pulls, &positions, &marks)
                .expect("GPU run");
            let mut mirror_pulls = pulls.clone();
            let mut flat = packed(&positions);
            let mut mirror_marks = marks.clone();
            let mut next_count = 0;
            let mut finals = vec![0.0f32; 3 * count];
            let target_words = packed(&targets);
            slayer::cpu::apply_moves(
                &ApplyParams::new(count, mode),
                &mut slayer::cpu::ApplyBuffers {
                    moving: &moving,
                    targets: &target_words,
                    pulls: &mut mirror_pulls,
                    positions: &mut flat,
                    marks: &mut mirror_marks,
                    next_count: &mut next_count,
                    finals: &mut finals,
                },
            );
            let label = format!("{mode:?} over {count} entries");
            let expected: Vec<Vec3> = bytemuck::cast_slice::<f32, Vec3>(&flat).to_vec();
            let scale = extent(&positions).max(extent(&targets));
            assert_close(
                &format!("{label}: positions"),
                &actual.positions,
                &expected,
                scale,
            );
            assert_eq!(actual.marks, mirror_marks, "{label}: marks");
            assert_eq!(actual.pulls, mirror_pulls, "{label}: amounts");
            assert_eq!(actual.next_count, next_count, "{label}: next count");
            if mode == ApplyMode::Gather {
                let finals = bytemuck::cast_slice::<f32, Vec3>(&finals);
                assert_close(&format!("{label}: finals"), &actual.finals, finals, scale);
            }
            // What each mode means, on the mirror: untouched vertices stay, entries move, and
            // a pull lands where `verdicts` (and `pull_back`) put it.
            let any_pulled = pulls.iter().any(|&p| p != 0);
            let flat_before = packed(&positions);
            let verdicts = slayer::gpu::verdicts(&moving, &flat_before, &pulls);
            for (k, entry) in moving.iter().enumerate() {
                let v = entry.vertex as usize;
                let now = expected[v];
                match mode {
                    ApplyMode::Place => assert_eq!(now, targets[k]),
                    ApplyMode::Pull if pulls[k] != 0 => {
                        assert_eq!(now.to_array(), verdicts[k].position)
                    }
                    ApplyMode::PullLast if pulls[k] != 0 => {
                        assert_eq!(now.to_array(), entry.start)
                    }
                    _ => assert_eq!(now, positions[v]),
                }
                let moved = now != Vec3::from_array(entry.start);
                match mode {
                    ApplyMode::MarkMoved => {
                        assert_eq!(mirror_marks[v], if moved { k as u32 + 1 } else { 0 })
                    }
                    ApplyMode::Clear | ApplyMode::Gather => assert_eq!(mirror_marks[v], 0),
                    _ => {}
                }
            }
            let pulls = matches!(mode, ApplyMode::Pull | ApplyMode::PullLast);
            assert_eq!(next_count != 0, pulls && any_pulled, "{label}");
        }
    }
}

/// The whole Jacobi loop of a step on the GPU (`GpuKernels::clamp`: targets placed, passes
/// sized by indirect dispatch, finals gathered) against `collide::clamp_moves`.
fn check_clamp_loop(scene: ProximityScene) {
    use slayer::pipeline::StepKernels;
    let mut kernels = slayer::gpu::GpuKernels::new(gpu());
    // On lavapipe the passes stay on the CPU unless asked: this test is about the GPU's.
    kernels.set_proximity_on_gpu(true);
    let mesh = &scene.mesh;
    let grid = SpatialHash::build(mesh, scene.edge).unwrap();
    let active = vec![true; mesh.layer_count()];
    let mut sorted = scene.order.clone();
    sorted.sort_unstable();
    let mut worst = 0.0f32;
    for size in [0, 1, 63, 64, 65, 1000, sorted.len()] {
        let selection: Vec<(u32, f32)> = sorted[..size.min(sorted.len())]
            .iter()
            .map(|&v| (v, 1.0))
            .collect();
        let targets: Vec<Vec3> = selection
            .iter()
            .map(|&(v, _)| scene.targets[v as usize])
            .collect();
        let before: Vec<Vec3> = selection
            .iter()
            .map(|&(v, _)| mesh.positions()[v as usize])
            .collect();
        let mut moved = mesh.clone();
        for (&(v, _), q) in selection.iter().zip(&targets) {
            moved.positions_mut()[v as usize] = *q;
        }
        let state = slayer::collide::StrokeState {
            grid: Some(&grid),
            active: &active,
            parallel: true,
            collision_distance: 0.5 * scene.edge,
            ring: 2,
            max_edge: mesh.longest_edge(),
            cull: true,
        };
        let (mut region, target_of) = gathered_region(&state, mesh, &selection, &targets);
        let mut on_cpu = mesh.clone();
        slayer::collide::clamp_moves(
            &state,
            &mut region,
            &mut on_cpu,
            (&selection, &targets, &target_of),
            &before,
        );
        let mut on_gpu = mesh.clone();
        let backstop = kernels.clamp(
            &state,
            &mut slayer::collide::Region::default(),
            &mut on_gpu,
            (&selection, &targets, &target_of),
            &before,
        );
        assert_eq!(kernels.failure(), None);
        // The GPU filtered the backstop's pairs too: no region needed.
        assert!(
            matches!(backstop, slayer::collide::Backstop::Undecided(_)),
            "{}: {backstop:?}",
            scene.name
        );
        let clamped = selection
            .iter()
            .zip(&targets)
            .filter(|&(&(v, _), q)| on_cpu.positions()[v as usize] != *q)
            .count();
        for (&(v, _), start) in selection.iter().zip(&before) {
            let (a, b) = (
                on_gpu.positions()[v as usize],
                on_cpu.positions()[v as usize],
            );
            // Either both moved it back to its start or neither did, and where it ended agrees.
            assert_eq!(a == *start, b == *start, "{}: vertex {v}", scene.name);
            worst = worst.max(a.distance(b) / scene.edge);
        }
        assert!(
            worst <= proximity_tolerance(&scene),
            "{}: {size} entries deviate by {worst} L",
            scene.name
        );
        if size >= 1000 {
            assert!(
                clamped * 4 >= size,
                "{}: only {clamped} clamped",
                scene.name
            );
        }
        // The GPU copy now holds the step's start again for the next one.
        let selected: Vec<u32> = selection.iter().map(|&(v, _)| v).collect();
        kernels.moved(&on_gpu, &selected, 0.0);
        kernels.moved(mesh, &selected, 0.0);
    }
    eprintln!("{}: clamp loop GPU vs CPU {worst:e} L", scene.name);
}

#[test]
fn clamp_loop_matches_the_cpu_pipeline_on_pressed_sheets() {
    check_clamp_loop(pressed_sheets());
}

#[test]
fn clamp_loop_matches_the_cpu_pipeline_on_a_folded_sheet() {
    check_clamp_loop(folded_sheet());
}
