//! The gate of a run recorded ahead (`longest_move`, `sample_gate`, `moved_edges`) against its
//! mirrors and the pipeline's bounds.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slayer::gpu::{GpuContext, SelectedVertex};
use slayer::mesh::INVALID;

use crate::common::{
    Binding, SIZES, bumpy_sheets, gpu, gpu_for_normals, half_moved_list, normal_params, packed,
    random_positions, shuffled,
};

#[test]
fn longest_move_matches_the_cpu_mirror_at_awkward_sizes() {
    // Selection lists of seeded distinct vertices at awkward sizes with targets up to half a
    // unit away; the list's room (`capacity`) equal to the count, a third short of it (the
    // entries past it are not the sample's), and above it. The GPU's `distance` may round
    // differently from the mirror's: a relative 1e-6. A NaN target counts as farther than any
    // finite move on both.
    let mut gpu = gpu();
    let vertex_count = 9000;
    let positions = random_positions(vertex_count, 920, 3.0);
    let flat = packed(&positions);
    let order = shuffled((0..vertex_count as u32).collect(), 921);
    let mut rng = ChaCha8Rng::seed_from_u64(922);
    for (k, &size) in SIZES.iter().enumerate() {
        if k + 1 == SIZES.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let selected: Vec<SelectedVertex> = order[..size]
            .iter()
            .map(|&vertex| SelectedVertex {
                vertex,
                weight: rng.random_range(0.01..1.0),
            })
            .collect();
        let targets: Vec<Vec3> = selected
            .iter()
            .map(|s| positions[s.vertex as usize] + random_positions(1, rng.random(), 0.29)[0])
            .collect();
        let flat_targets = packed(&targets);
        for capacity in [size, size - size / 3, size + 5] {
            let count = size as u32;
            let params =
                slayer::gpu::GateParams::new(capacity, slayer::gpu::GateStage::Decide, (0.0, 0.0));
            let mut mirror = slayer::gpu::GateStatus::default();
            slayer::cpu::longest_move(
                &params,
                (&flat, &flat_targets),
                (&selected, count),
                &mut mirror,
            );
            let expected = selected
                .iter()
                .zip(&targets)
                .take(capacity.min(size))
                .map(|(s, t)| positions[s.vertex as usize].distance(*t))
                .fold(0.0f32, f32::max);
            assert_eq!(mirror.longest_move(), expected, "mirror at size {size}");
            let actual = slayer::gpu::run_longest_move(
                &gpu,
                (&positions, &targets),
                (&selected, count),
                capacity,
                slayer::gpu::GateStatus::default(),
            )
            .expect("GPU run");
            assert_eq!(actual.stopped, 0);
            let deviation = (actual.longest_move() - expected).abs();
            assert!(
                deviation <= 1e-6 * expected,
                "size {size} capacity {capacity}: GPU {} mirror {expected}",
                actual.longest_move()
            );
        }
    }
    // A longer move already in the status stays; a NaN target beats every finite move.
    let selected: Vec<SelectedVertex> = (0..100)
        .map(|vertex| SelectedVertex {
            vertex,
            weight: 1.0,
        })
        .collect();
    let mut targets: Vec<Vec3> = selected
        .iter()
        .map(|s| positions[s.vertex as usize] + Vec3::X)
        .collect();
    let held = slayer::gpu::GateStatus {
        longest: 5.0f32.to_bits(),
        ..Default::default()
    };
    let kept =
        slayer::gpu::run_longest_move(&gpu, (&positions, &targets), (&selected, 100), 100, held)
            .expect("GPU run");
    assert_eq!(kept.longest_move(), 5.0);
    targets[57] = Vec3::new(f32::NAN, 0.0, 0.0);
    let flat_targets = packed(&targets);
    let params = slayer::gpu::GateParams::new(100, slayer::gpu::GateStage::Decide, (0.0, 0.0));
    let mut mirror = slayer::gpu::GateStatus::default();
    slayer::cpu::longest_move(
        &params,
        (&flat, &flat_targets),
        (&selected, 100),
        &mut mirror,
    );
    let actual = slayer::gpu::run_longest_move(
        &gpu,
        (&positions, &targets),
        (&selected, 100),
        100,
        slayer::gpu::GateStatus::default(),
    )
    .expect("GPU run");
    for (status, who) in [(mirror, "mirror"), (actual, "GPU")] {
        assert!(
            status.longest > f32::MAX.to_bits(),
            "{who}: a NaN move read as {}",
            status.longest_move()
        );
    }
}

/// One `sample_gate` stage on the GPU and in the mirror, which must agree; the GPU's result.
fn gate_stage(
    gpu: &GpuContext,
    params: &slayer::gpu::GateParams,
    overflows: u32,
    (count, moving, status): (u32, &[slayer::gpu::MovingVertex], slayer::gpu::GateStatus),
) -> (u32, Vec<slayer::gpu::MovingVertex>, slayer::gpu::GateStatus) {
    let mut mirror = (count, moving.to_vec(), status);
    slayer::cpu::sample_gate(
        params,
        overflows,
        slayer::cpu::GateState {
            selection_count: &mut mirror.0,
            moving: &mut mirror.1,
            status: &mut mirror.2,
        },
    );
    let actual = slayer::gpu::run_sample_gate(gpu, params, overflows, (count, moving, status))
        .expect("GPU run");
    assert_eq!(actual, mirror, "{params:?} overflows {overflows}");
    actual
}

#[test]
fn sample_gate_stages_match_the_cpu_mirror() {
    use slayer::gpu::{GateParams, GateStage, GateStatus, MovingVertex};
    let mut gpu = gpu();
    // Opening: the longest move reset; the selection emptied only in a stopped run.
    for stopped in [0, GateStatus::MOVE, GateStatus::EARLIER] {
        let status = GateStatus {
            stopped,
            longest: 7.5f32.to_bits(),
            edge: 2.0f32.to_bits(),
            deferred: 0,
        };
        let open = GateParams::new(0, GateStage::Open, (0.0, 0.0));
        let (count, _, after) = gate_stage(&gpu, &open, 0, (77, &[], status));
        assert_eq!(
            after,
            GateStatus {
                longest: 0,
                ..status
            }
        );
        assert_eq!(count, if stopped == 0 { 77 } else { 0 });
    }
    // The verdict, over every combination of the five reasons, the move and the edge bound on
    // either side of the assumed ones, equal to them, and NaN.
    let assumed = 0.25f32;
    let max_edge = 1.5f32;
    let around = |x: f32| [0.0f32, x, f32::from_bits(x.to_bits() + 1), f32::NAN];
    let capacity = 64;
    for stopped_before in [0, GateStatus::SELECTION] {
        for count in [capacity as u32, capacity as u32 + 1] {
            for overflows in [0, 3] {
                for (longest, edge) in around(assumed)
                    .into_iter()
                    .flat_map(|l| around(max_edge).map(move |e| (l, e)))
                {
                    let status = GateStatus {
                        stopped: stopped_before,
                        longest: longest.to_bits(),
                        edge: edge.to_bits(),
                        deferred: 0,
                    };
                    let decide = GateParams::new(capacity, GateStage::Decide, (assumed, max_edge));
                    let (after_count, _, after) =
                        gate_stage(&gpu, &decide, overflows, (count, &[], status));
                    let mut expected = 0;
                    if stopped_before != 0 {
                        expected |= GateStatus::EARLIER;
                    }
                    if count as usize > capacity {
                        expected |= GateStatus::SELECTION;
                    }
                    if overflows != 0 {
                        expected |= GateStatus::RINGS;
                    }
                    if longest.is_nan() || longest > assumed {
                        expected |= GateStatus::MOVE;
                    }
                    if edge.is_nan() || edge > max_edge {
                        expected |= GateStatus::EDGES;
                    }
                    assert_eq!(
                        after.stopped, expected,
                        "count {count} longest {longest} edge {edge}"
                    );
                    assert_eq!(
                        (after_count, after.longest, after.edge),
                        (count, longest.to_bits(), edge.to_bits())
                    );
                }
            }
        }
    }
    // Vacating: every slot up to the capacity of a stopped run, none of one that holds; the
    // slots past the capacity untouched.
    for (k, &size) in SIZES.iter().enumerate() {
        if k + 1 == SIZES.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let moving: Vec<MovingVertex> = (0..size as u32)
            .map(|i| MovingVertex {
                start: [i as f32, 0.0, 1.0],
                vertex: if i % 5 == 4 { INVALID } else { 3 * i },
                layer: i % 3,
                ring_start: 4 * i,
                ring_end: 4 * i + 2,
                _pad: 0,
            })
            .collect();
        let capacity = size - size / 4;
        for stopped in [0, GateStatus::RINGS] {
            let vacate = GateParams::new(capacity, GateStage::Vacate, (assumed, max_edge));
            let status = GateStatus {
                stopped,
                ..Default::default()
            };
            let (_, after, _) = gate_stage(&gpu, &vacate, 0, (size as u32, &moving, status));
            for (i, (a, m)) in after.iter().zip(&moving).enumerate() {
                let vacated = stopped != 0 && i < capacity;
                let expected = MovingVertex {
                    vertex: if vacated { INVALID } else { m.vertex },
                    ..*m
                };
                assert_eq!(*a, expected, "size {size} slot {i} stopped {stopped}");
            }
        }
    }
}

#[test]
fn moved_edges_grow_the_edge_bound_as_the_cpu_mirror_and_the_pipeline_do() {
    check_moved_edges(Binding::Whole);
}

#[test]
fn moved_edges_read_a_topology_split_over_several_bindings() {
    check_moved_edges(Binding::Paged);
}

fn check_moved_edges(binding: Binding) {
    // Moving lists over a seeded shuffle of the vertices of two bumpy sheets at awkward sizes
    // (the largest folded into two dimensions), one slot in seven vacant, about half the
    // entries moved (some far enough to stretch their faces past the mesh's longest edge).
    // The bound grows to the longest edge of the faces around the moved vertices, as the
    // pipeline's `longest_edge` over them; `distance` may round differently on the GPU: a
    // relative 1e-6.
    let start = bumpy_sheets();
    let mut gpu = gpu_for_normals(binding, &start);
    let vertex_count = start.vertex_count();
    let topology = slayer::gpu::PackedTopology::of(&start);
    let order = shuffled((0..vertex_count as u32).collect(), 931);
    let mut rng = ChaCha8Rng::seed_from_u64(932);
    let initial = start.longest_edge();
    let sizes = SIZES.map(|size| size.min(vertex_count));
    for (k, &size) in sizes.iter().enumerate() {
        if k + 1 == sizes.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let mut mesh = start.clone();
        let (moving, moved) = half_moved_list(
            start.positions(),
            mesh.positions_mut(),
            &order[..size],
            (&mut rng, |rng| {
                Vec3::new(0.0, 0.0, rng.random_range(0.001..2.0) * initial)
            }),
        );
        let before = slayer::gpu::GateStatus::starting(0.5 * initial);
        let params = normal_params(size, &topology);
        let flat = packed(mesh.positions());
        let mut mirror = before;
        slayer::cpu::moved_edges(&params, (&flat, &topology.words), &moving, &mut mirror);
        // What the pipeline's bound grows to: the longest edge of the faces around the moved
        // vertices.
        let expected = moved
            .iter()
            .flat_map(|&v| mesh.faces_around(v))
            .map(|f| {
                let [a, b, c] = mesh.face_positions(f as usize);
                a.distance(b).max(b.distance(c)).max(c.distance(a))
            })
            .fold(before.edge_bound(), f32::max);
        assert_eq!(mirror.edge_bound(), expected, "mirror at size {size}");
        let actual = slayer::gpu::run_moved_edges(&gpu, &mesh, &moving, before).expect("GPU run");
        assert_eq!((actual.stopped, actual.longest), (0, 0));
        let deviation = (actual.edge_bound() - expected).abs();
        assert!(
            deviation <= 1e-6 * expected,
            "size {size}: GPU {} mirror {expected}",
            actual.edge_bound()
        );
    }
}

/// A start whose split steps follow defers a move over the step limit, by at most twice, to
/// them instead of stopping the run: it moves nothing, they run; a start that does not defer
/// leaves them empty and vacated; the next ordinary call clears the deferral. The GPU and the
/// mirror agree at every stage, and on the bounds (the limit, twice it, the floats beside,
/// NaN).
#[test]
fn a_start_defers_a_move_of_two_steps_to_its_split_steps_as_the_mirror_does() {
    use slayer::gpu::{GateParams, GateSplit, GateStage, GateStatus, MovingVertex};
    let gpu = gpu();
    let (limit, assumed, max_edge) = (0.5f32, 0.25f32, 1.5f32);
    let start = GateSplit {
        defer_over: limit,
        if_deferred: false,
    };
    let split = GateSplit {
        defer_over: 0.0,
        if_deferred: true,
    };
    let beside = |x: f32| {
        [
            f32::from_bits(x.to_bits() - 1),
            x,
            f32::from_bits(x.to_bits() + 1),
        ]
    };
    let moves = [0.1, assumed, 0.4, 0.75, f32::NAN]
        .into_iter()
        .chain(beside(limit))
        .chain(beside(2.0 * limit));
    let moving: Vec<MovingVertex> = (0..10u32)
        .map(|i| MovingVertex {
            start: [i as f32, 0.0, 0.0],
            vertex: 2 * i,
            layer: 0,
            ring_start: i,
            ring_end: i + 1,
            _pad: 0,
        })
        .collect();
    let capacity = moving.len();
    for longest in moves {
        let status = GateStatus {
            longest: longest.to_bits(),
            ..GateStatus::starting(max_edge)
        };
        let decide = GateParams::new(capacity, GateStage::Decide, (assumed, max_edge));
        let (_, _, decided) = gate_stage(&gpu, &decide.split(start), 0, (7, &[], status));
        let defers = longest > limit && longest <= 2.0 * limit;
        let held = longest <= assumed;
        assert_eq!(decided.deferred, u32::from(defers), "move {longest}");
        let stopped = if defers || held { 0 } else { GateStatus::MOVE };
        assert_eq!(decided.stopped, stopped, "move {longest}");
        // The start's own moves are vacated when it deferred (or stopped).
        let vacate = GateParams::new(capacity, GateStage::Vacate, (0.0, 0.0));
        let (_, after, _) = gate_stage(&gpu, &vacate.split(start), 0, (7, &moving, decided));
        let vacated = after.iter().filter(|m| m.vertex == INVALID).count();
        assert_eq!(vacated, if held { 0 } else { capacity }, "move {longest}");
        // Each split step selects, and keeps its moves, only after a start that deferred.
        let open = GateParams::new(0, GateStage::Open, (0.0, 0.0)).split(split);
        let (count, _, opened) = gate_stage(&gpu, &open, 0, (7, &[], decided));
        assert_eq!(count, if defers { 7 } else { 0 }, "move {longest}");
        let step_decide = GateParams::new(capacity, GateStage::Decide, (limit, max_edge));
        let (_, _, step) = gate_stage(&gpu, &step_decide.split(split), 0, (count, &[], opened));
        assert_eq!(step.deferred, decided.deferred, "a step keeps the deferral");
        let (_, after, _) = gate_stage(&gpu, &vacate.split(split), 0, (count, &moving, step));
        let vacated = after.iter().filter(|m| m.vertex == INVALID).count();
        assert_eq!(vacated, if defers { 0 } else { capacity }, "move {longest}");
        // The next ordinary call opens as in a run that never deferred.
        let ordinary = GateParams::new(0, GateStage::Open, (0.0, 0.0));
        let (count, _, next) = gate_stage(&gpu, &ordinary, 0, (7, &[], step));
        assert_eq!(
            (count, next.deferred),
            (if step.stopped == 0 { 7 } else { 0 }, 0)
        );
    }
}
