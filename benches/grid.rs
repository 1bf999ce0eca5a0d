//! The spatial hash on a generated layered scene: building it, brush-sized sphere queries,
//! broad-phase face candidates, and moving vertices (the per-step grid update).

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use slayer::grid::SpatialHash;
use slayer::scene::{SceneKind, SceneSpec, generate};
use std::hint::black_box;

fn grid(c: &mut Criterion) {
    let mesh = generate(&SceneSpec {
        kind: SceneKind::Plaster,
        triangles: 200_000,
        seed: 1,
    })
    .unwrap();
    let stats = mesh.edge_length_stats();
    let l = stats.mean as f32;
    let csr = mesh.vertex_faces();
    let grid = SpatialHash::build(&mesh, l).unwrap();
    let center = mesh.positions()[mesh.vertex_count() / 2];

    let mut group = c.benchmark_group("grid");
    group.sample_size(20);
    group.bench_function("build 200K faces", |b| {
        b.iter(|| SpatialHash::build(black_box(&mesh), l).unwrap())
    });
    group.bench_function("sphere query r=12L", |b| {
        let mut out = Vec::new();
        b.iter(|| {
            out.clear();
            grid.vertices_in_sphere(mesh.positions(), black_box(center), 12.0 * l, &mut out);
            out.len()
        })
    });
    group.bench_function("candidate faces r=L", |b| {
        let mut out = Vec::new();
        b.iter(|| {
            out.clear();
            grid.candidate_faces(&csr, black_box(center), l, stats.max as f32, &mut out);
            out.len()
        })
    });
    group.bench_function("move 1000 vertices by L/2", |b| {
        let mut moving = grid.clone();
        let mut offset = 0.5 * l;
        b.iter(|| {
            offset = -offset;
            for v in 0..1000u32 {
                let p = mesh.positions()[v as usize] + Vec3::splat(offset);
                moving.move_to(v, p);
            }
        })
    });
    group.finish();
}

criterion_group!(benches, grid);
criterion_main!(benches);
