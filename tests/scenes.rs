//! Generated scenes: size within ±5 %, near-uniform edges, layers a few edge lengths apart,
//! disconnected patches in upper layers, no intersections, and byte-identical output per seed.

use slayer::collide::{find_intersections, smallest_layer_gap};
use slayer::io::{Format, encode_mesh};
use slayer::mesh::Mesh;
use slayer::scene::{SceneKind, SceneSpec, generate};

fn scene(kind: SceneKind, triangles: usize, seed: u64) -> Mesh {
    generate(&SceneSpec {
        kind,
        triangles,
        seed,
    })
    .unwrap_or_else(|e| panic!("{kind}: {e}"))
}

#[test]
fn sizes_land_within_five_percent() {
    for kind in SceneKind::ALL {
        for triangles in [2_000, 15_000, 60_000] {
            let mesh = scene(kind, triangles, 3);
            let ratio = mesh.live_face_count() as f64 / triangles as f64;
            assert!(
                (0.95..=1.05).contains(&ratio),
                "{kind} at {triangles}: {} faces",
                mesh.live_face_count()
            );
        }
    }
}

#[test]
fn layered_scenes_are_clean_uniform_and_separated() {
    let expected_layers = [
        (SceneKind::Plaster, 3),
        (SceneKind::Bark, 4),
        (SceneKind::Metal, 3),
    ];
    for (kind, layers) in expected_layers {
        let mesh = scene(kind, 40_000, 1);
        mesh.validate().unwrap_or_else(|e| panic!("{kind}: {e}"));
        assert_eq!(mesh.layer_count(), layers, "{kind}");
        assert!(
            mesh.faces_per_layer().iter().all(|&f| f > 0),
            "{kind}: empty layer"
        );
        let stats = mesh.edge_length_stats();
        assert!(
            stats.coefficient_of_variation() <= 0.15,
            "{kind}: edge cv {}",
            stats.coefficient_of_variation()
        );
        // Upper layers are broken into several patches.
        let per_layer = mesh.components().per_layer(layers);
        assert!(
            per_layer[layers - 1] >= 3,
            "{kind}: top layer has {per_layer:?} patches"
        );
        // Layers float a few edge lengths apart: at least two everywhere.
        let l = stats.mean as f32;
        let gap = smallest_layer_gap(&mesh, 4.0 * l)
            .unwrap()
            .unwrap_or(f32::INFINITY);
        assert!(
            gap >= 2.0 * l,
            "{kind}: layers only {} edge lengths apart",
            gap / l
        );
        assert_eq!(find_intersections(&mesh).total(), 0, "{kind}");
    }
}

#[test]
fn closed_sphere_and_open_plane() {
    let sphere = scene(SceneKind::Sphere, 20_000, 1);
    sphere.validate().unwrap();
    assert!((0..sphere.vertex_count() as u32).all(|v| !sphere.is_boundary_vertex(v)));
    let chi = sphere.live_vertex_count() as i64 - sphere.edges().len() as i64
        + sphere.live_face_count() as i64;
    assert_eq!(chi, 2);
    assert!(sphere.edge_length_stats().coefficient_of_variation() <= 0.15);
    let plane = scene(SceneKind::Plane, 20_000, 1);
    plane.validate().unwrap();
    assert_eq!(plane.components().count(), 1);
}

#[test]
fn same_arguments_give_identical_bytes() {
    for kind in [
        SceneKind::Plaster,
        SceneKind::Bark,
        SceneKind::Metal,
        SceneKind::Sphere,
    ] {
        let a = scene(kind, 8_000, 7);
        let b = scene(kind, 8_000, 7);
        for format in [Format::Obj, Format::Ply] {
            assert!(
                encode_mesh(&a, format) == encode_mesh(&b, format),
                "{kind} {format:?}"
            );
        }
    }
    let a = scene(SceneKind::Plaster, 8_000, 7);
    let c = scene(SceneKind::Plaster, 8_000, 8);
    assert!(
        encode_mesh(&a, Format::Ply) != encode_mesh(&c, Format::Ply),
        "the seed matters"
    );
}

#[test]
fn bad_scene_arguments_are_errors() {
    assert!("marble".parse::<SceneKind>().is_err());
    for triangles in [0, 10, usize::MAX] {
        let spec = SceneSpec {
            kind: SceneKind::Plaster,
            triangles,
            seed: 1,
        };
        assert!(generate(&spec).is_err(), "{triangles}");
    }
}
