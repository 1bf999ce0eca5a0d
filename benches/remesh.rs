//! One whole-mesh remesh (`slayer remesh`, `remesh::remesh_all`) of a jittered sphere at 100K
//! and 1M faces toward its own mean edge, and one refinement of a 20K-face sphere eightfold
//! (through subdivision). The 1M case takes half a minute an iteration: it runs under
//! `cargo bench` only, not when `cargo test --all-targets` runs each bench once.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use slayer::mesh::Mesh;
use slayer::remesh::{RemeshSettings, remesh_all};
use slayer::scene::{SceneKind, SceneSpec, generate, jitter};

/// The sphere scene at `triangles` faces, each vertex moved up to 0.3 edges along the surface:
/// an uneven mesh for the remesher to even out.
fn jittered_sphere(triangles: usize) -> Mesh {
    let mut mesh = generate(&SceneSpec {
        kind: SceneKind::Sphere,
        triangles,
        seed: 1,
    })
    .unwrap();
    jitter(&mut mesh, 0.3, 7).unwrap();
    mesh
}

fn remesh(c: &mut Criterion) {
    let mut group = c.benchmark_group("remesh");
    group.sample_size(10);
    // `cargo bench` passes `--bench`; the test run of the benches does not.
    let benching = std::env::args().any(|a| a == "--bench");
    let sizes: &[(&str, usize)] = if benching {
        &[("100K", 100_000), ("1M", 1_000_000)]
    } else {
        &[("100K", 100_000)]
    };
    for &(label, triangles) in sizes {
        let mesh = jittered_sphere(triangles);
        let settings = RemeshSettings::new(mesh.mean_edge_length());
        group.bench_function(format!("jittered sphere {label} at its mean edge"), |b| {
            b.iter_batched(
                || mesh.clone(),
                |mut mesh| remesh_all(&mut mesh, &settings).unwrap(),
                BatchSize::LargeInput,
            )
        });
    }
    let small = generate(&SceneSpec {
        kind: SceneKind::Sphere,
        triangles: 20_000,
        seed: 1,
    })
    .unwrap();
    let refine = RemeshSettings::new(small.mean_edge_length() / 8.0);
    group.bench_function("sphere 20K refined eightfold", |b| {
        b.iter_batched(
            || small.clone(),
            |mut mesh| remesh_all(&mut mesh, &refine).unwrap(),
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

criterion_group!(benches, remesh);
criterion_main!(benches);
