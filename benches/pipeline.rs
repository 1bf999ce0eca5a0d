//! The brush pipeline's phases on their own (CPU): selection through the grid, deformation,
//! and collision (proximity clamping plus the exact backstop) for one draw dab pressing the
//! upper layers of a 200K-face plaster scene into the base; and the collision phase alone,
//! culled and not (`PipelineSettings::cull`), for a draw on a 1M-face flat sheet, an inflate
//! on a 200K-face sphere and the plaster dab.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use glam::Vec3;
use slayer::brush::{Brush, BrushKind, Dab, DabFrame, Falloff};
use slayer::collide::neighbourhood::exclusion_ring;
use slayer::collide::{Region, StrokeState, collide};
use slayer::grid::SpatialHash;
use slayer::mesh::{INVALID, Mesh};
use slayer::pipeline::step::{deform, select};
use slayer::scene::{SceneKind, SceneSpec, generate};
use std::hint::black_box;

/// The whole stroke's state for `mesh`, filed in `grid` (cell = the mean edge, which is also
/// the collision distance), on all cores.
fn stroke_state<'a>(
    mesh: &Mesh,
    grid: &'a SpatialHash,
    active: &'a [bool],
    cull: bool,
) -> StrokeState<'a> {
    let edge = grid.cell_size();
    StrokeState {
        grid: Some(grid),
        active,
        parallel: true,
        collision_distance: edge,
        ring: exclusion_ring(mesh, edge),
        max_edge: mesh.edge_length_stats().max as f32,
        cull,
    }
}

/// Runs `f` on a thread of rayon's pool, as the pipeline runs a stroke's steps
/// (`StrokeInProgress::add_samples`); the hand-over costs some microseconds per call.
fn in_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::scope(|_| f())
}

fn phases(c: &mut Criterion) {
    let mesh = generate(&SceneSpec {
        kind: SceneKind::Plaster,
        triangles: 200_000,
        seed: 1,
    })
    .unwrap();
    let edge = mesh.mean_edge_length();
    let grid = SpatialHash::build(&mesh, edge).unwrap();
    let active = vec![false, true, true];
    let state = stroke_state(&mesh, &grid, &active, true);
    // The middle of the paint layer, pushed down hard.
    let (lo, hi) = mesh.bounds().unwrap();
    let center = (lo + hi) * 0.5;
    let top = (0..mesh.vertex_count())
        .filter(|&v| mesh.vertex_layers()[v] == 1)
        .min_by(|&a, &b| {
            mesh.positions()[a]
                .truncate()
                .distance(center.truncate())
                .total_cmp(&mesh.positions()[b].truncate().distance(center.truncate()))
        })
        .unwrap();
    let dab = Dab {
        brush: Brush {
            kind: BrushKind::Draw,
            radius: 12.0 * edge,
            strength: 1.0,
            falloff: Falloff::blend(3),
            invert: true,
        },
        frame: DabFrame {
            center: mesh.positions()[top],
            normal: Vec3::Z,
            plane_point: mesh.positions()[top],
            motion: Vec3::ZERO,
        },
        pressure: 1.0,
        share: 1.0,
    };
    let selection = select(&state, &mesh, &dab);
    let targets = deform(&state, &mesh, &dab, &selection);
    let mut target_of = vec![INVALID; mesh.vertex_count()];
    for (i, &(v, _)) in selection.iter().enumerate() {
        target_of[v as usize] = i as u32;
    }

    let mut group = c.benchmark_group("pipeline");
    group.sample_size(30);
    group.bench_function(format!("select ({} vertices)", selection.len()), |b| {
        b.iter(|| in_pool(|| select(&state, black_box(&mesh), &dab).len()))
    });
    group.bench_function("deform", |b| {
        b.iter(|| in_pool(|| deform(&state, black_box(&mesh), &dab, &selection).len()))
    });
    let mut region = Region::default();
    group.bench_function("collide", |b| {
        b.iter_batched_ref(
            || mesh.clone(),
            |m| {
                in_pool(|| {
                    collide(&state, &mut region, m, &selection, &targets, &target_of).clamped
                })
            },
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

/// One dab's collision phase, culled and searched, at the centre of a scene's top layer.
fn collision_alone(c: &mut Criterion, kind: SceneKind, triangles: usize, brush: BrushKind) {
    let mesh = generate(&SceneSpec {
        kind,
        triangles,
        seed: 1,
    })
    .unwrap();
    let edge = mesh.mean_edge_length();
    let grid = SpatialHash::build(&mesh, edge).unwrap();
    let top_layer = mesh.layer_count() as u32 - 1;
    let active: Vec<bool> = (0..=top_layer).map(|l| l == top_layer).collect();
    let (lo, hi) = mesh.bounds().unwrap();
    let above = Vec3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, hi.z);
    let center = (0..mesh.vertex_count())
        .filter(|&v| mesh.vertex_layers()[v] == top_layer)
        .map(|v| mesh.positions()[v])
        .min_by(|a, b| a.distance(above).total_cmp(&b.distance(above)))
        .unwrap();
    let dab = Dab {
        brush: Brush {
            kind: brush,
            radius: 0.05 * (hi - lo).x,
            strength: 0.5,
            falloff: Falloff::blend(3),
            // Pressing into what lies below.
            invert: brush == BrushKind::Draw,
        },
        frame: DabFrame {
            center,
            normal: Vec3::Z,
            plane_point: center,
            motion: Vec3::ZERO,
        },
        pressure: 1.0,
        share: 1.0,
    };
    let mut group = c.benchmark_group(format!("collision alone: {kind} {triangles} faces"));
    group.sample_size(20);
    for cull in [true, false] {
        let state = stroke_state(&mesh, &grid, &active, cull);
        let selection = select(&state, &mesh, &dab);
        let targets = deform(&state, &mesh, &dab, &selection);
        let mut target_of = vec![INVALID; mesh.vertex_count()];
        for (i, &(v, _)) in selection.iter().enumerate() {
            target_of[v as usize] = i as u32;
        }
        let mut region = Region::default();
        let name = if cull { "culled" } else { "searched" };
        group.bench_function(format!("{brush:?} {name}"), |b| {
            b.iter_batched_ref(
                || mesh.clone(),
                |m| {
                    in_pool(|| {
                        collide(&state, &mut region, m, &selection, &targets, &target_of).clamped
                    })
                },
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

fn collision(c: &mut Criterion) {
    collision_alone(c, SceneKind::Plane, 1_000_000, BrushKind::Draw);
    collision_alone(c, SceneKind::Sphere, 200_000, BrushKind::Inflate);
    collision_alone(c, SceneKind::Plaster, 200_000, BrushKind::Draw);
}

criterion_group!(benches, phases, collision);
criterion_main!(benches);
