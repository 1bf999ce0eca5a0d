//! The exact triangle–triangle test on hand-made cases, and the whole-mesh count against an
//! all-pairs brute force.

use glam::Vec3;
use proptest::prelude::*;
use slayer::collide::find_intersections;
use slayer::geom::{neighbours_overlap, triangles_intersect};
use slayer::mesh::Mesh;
use slayer::scene::shapes;

fn t(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> [Vec3; 3] {
    [Vec3::from(a), Vec3::from(b), Vec3::from(c)]
}

#[test]
fn hand_made_cases() {
    let base = t([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]);
    let cases = [
        (
            "piercing",
            t([0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [1.5, 1.5, 1.0]),
            true,
        ),
        (
            "above",
            t([0.5, 0.5, 0.1], [1.0, 0.5, 0.2], [0.5, 1.0, 0.3]),
            false,
        ),
        (
            "touching at a corner from above",
            t([0.5, 0.5, 0.0], [1.0, 0.5, 1.0], [0.5, 1.0, 1.0]),
            true,
        ),
        (
            "edge on the surface",
            t([0.2, 0.2, 0.0], [1.0, 0.2, 0.0], [0.5, 0.5, 1.0]),
            true,
        ),
        (
            "coplanar overlapping",
            t([0.5, 0.5, 0.0], [3.0, 0.5, 0.0], [0.5, 3.0, 0.0]),
            true,
        ),
        (
            "coplanar containing",
            t([0.1, 0.1, 0.0], [0.3, 0.1, 0.0], [0.1, 0.3, 0.0]),
            true,
        ),
        (
            "coplanar apart",
            t([3.0, 3.0, 0.0], [4.0, 3.0, 0.0], [3.0, 4.0, 0.0]),
            false,
        ),
        (
            "coplanar sharing an edge line",
            t([2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [2.0, 2.0, 0.0]),
            true,
        ),
        (
            "crossing the plane beside it",
            t([3.0, 3.0, -1.0], [3.0, 3.0, 1.0], [4.0, 3.0, 0.0]),
            false,
        ),
        (
            "parallel below",
            t([0.0, 0.0, -1e-7], [2.0, 0.0, -1e-7], [0.0, 2.0, -1e-7]),
            false,
        ),
        (
            "degenerate segment piercing",
            t([0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [0.5, 0.5, 0.0]),
            true,
        ),
        (
            "degenerate segment beside",
            t([3.5, 0.5, -1.0], [3.5, 0.5, 1.0], [3.5, 0.5, 0.0]),
            false,
        ),
    ];
    for (name, other, expected) in cases {
        assert_eq!(triangles_intersect(base, other), expected, "{name}");
        assert_eq!(
            triangles_intersect(other, base),
            expected,
            "{name} (swapped)"
        );
    }
}

#[test]
fn nearly_touching_is_decided_exactly() {
    // One f32 step below the plane is apart, on the plane touches: no tolerance either way.
    let base = t([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let below = -f32::from_bits(1); // the smallest negative subnormal
    let apart = t([0.25, 0.25, below], [0.5, 0.25, -1.0], [0.25, 0.5, -1.0]);
    let touching = t([0.25, 0.25, 0.0], [0.5, 0.25, -1.0], [0.25, 0.5, -1.0]);
    assert!(!triangles_intersect(base, apart));
    assert!(triangles_intersect(base, touching));
}

/// Every pair of faces: (between layers, within a layer, folded onto a neighbour).
fn brute_force(mesh: &Mesh) -> (usize, usize, usize) {
    let (mut between, mut within, mut folded) = (0, 0, 0);
    for a in 0..mesh.face_count() {
        for b in a + 1..mesh.face_count() {
            let (fa, fb) = (mesh.faces()[a], mesh.faces()[b]);
            let (ta, tb) = (mesh.face_positions(a), mesh.face_positions(b));
            if fa.iter().any(|v| fb.contains(v)) {
                folded += usize::from(neighbours_overlap(ta, fa, tb, fb));
            } else if triangles_intersect(ta, tb) {
                if mesh.face_layers()[a] == mesh.face_layers()[b] {
                    within += 1;
                } else {
                    between += 1;
                }
            }
        }
    }
    (between, within, folded)
}

fn counts(mesh: &Mesh) -> (usize, usize, usize) {
    let report = find_intersections(mesh);
    (
        report.between_layers,
        report.within_layers,
        report.folded_neighbours,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// Two sheets squeezed together with random bumps: the grid count equals all pairs.
    #[test]
    fn grid_count_matches_all_pairs(
        gap in 0.0f32..1.0,
        bumps in prop::collection::vec((0usize..72, -1.5f32..1.5), 0..12),
    ) {
        let mut mesh = shapes::stacked_sheets(2, 5, 5, 1.0, gap);
        let n = mesh.vertex_count();
        for (v, dz) in bumps {
            mesh.positions_mut()[v % n].z += dz;
        }
        prop_assert_eq!(counts(&mesh), brute_force(&mesh));
    }
}

/// Sheets crumpled in all three directions, from gently to past folding: the count, which skips
/// the pairs around vertices whose fans project one-to-one, equals all pairs tested one by one.
/// Both flat fans and folds onto neighbours must occur, or the comparison proves little.
#[test]
fn crumpled_sheets_count_as_all_pairs_do() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(48);
    let mut folded = 0;
    for case in 0..60 {
        let mut mesh = shapes::stacked_sheets(2, 7, 7, 1.0, 1.0);
        let amplitude = 0.6 * case as f32 / 60.0;
        for p in mesh.positions_mut() {
            *p += Vec3::from_array([(); 3].map(|_| rng.random_range(-amplitude..=amplitude)));
        }
        let (found, all_pairs) = (counts(&mesh), brute_force(&mesh));
        assert_eq!(found, all_pairs, "case {case}, amplitude {amplitude}");
        folded += found.2;
    }
    assert!(
        folded > 20,
        "only {folded} folded neighbours over the cases"
    );
}

#[test]
fn a_layer_pushed_through_another_is_counted() {
    let mut mesh = shapes::stacked_sheets(2, 8, 8, 1.0, 1.0);
    assert_eq!(find_intersections(&mesh).total(), 0);
    // Push the middle of the top sheet through the bottom one.
    let middle = 81 + 4 * 9 + 4;
    mesh.positions_mut()[middle].z = -1.0;
    let report = find_intersections(&mesh);
    assert!(
        report.between_layers > 0 && report.within_layers == 0,
        "{report:?}"
    );
    assert_eq!(counts(&mesh), brute_force(&mesh));
}

#[test]
fn self_intersection_within_a_layer_is_counted_but_neighbours_touching_are_not() {
    // A sheet folded through itself: lift one corner vertex across a far part of the sheet.
    let mut mesh = shapes::stacked_sheets(1, 6, 6, 1.0, 0.0);
    assert_eq!(
        find_intersections(&mesh).total(),
        0,
        "adjacent faces share vertices"
    );
    mesh.positions_mut()[0] = Vec3::new(3.2, 3.3, 0.0) + Vec3::new(0.0, 0.0, 0.0);
    let report = find_intersections(&mesh);
    assert!(report.within_layers > 0);
    assert_eq!(counts(&mesh), brute_force(&mesh));
}

#[test]
fn absurd_coordinates_stay_bounded() {
    // A face spanning a huge box goes to the oversized path instead of millions of cells.
    let mut mesh = shapes::stacked_sheets(2, 4, 4, 1.0, 2.0);
    mesh.positions_mut()[0] = Vec3::new(1e12, -1e12, 5e11);
    assert_eq!(counts(&mesh), brute_force(&mesh));
    mesh.positions_mut()[1] = Vec3::new(f32::NAN, 0.0, 0.0);
    assert!(find_intersections(&mesh).skipped_faces > 0);
}

/// A face folded flat onto the faces around it shares vertices with them, which the pair test
/// skips: the neighbour test counts it, and `check` reports it.
#[test]
fn a_face_folded_onto_its_neighbours_is_counted() {
    let mut mesh = shapes::stacked_sheets(1, 4, 4, 1.0, 0.0);
    assert_eq!(counts(&mesh), (0, 0, 0));
    // The corner vertex pulled across its own fan, in the sheet's plane: its faces now lie on
    // their neighbours.
    mesh.positions_mut()[0] = Vec3::new(1.5, 1.5, 0.0);
    let (_, _, folded) = counts(&mesh);
    assert!(folded > 0, "{:?}", find_intersections(&mesh));
    assert_eq!(counts(&mesh), brute_force(&mesh));
    assert_eq!(
        find_intersections(&mesh).total(),
        counts(&mesh).0 + counts(&mesh).1 + folded
    );
    let notes = slayer::io::ImportReport::default();
    let report = slayer::check::check_mesh(&mesh, &notes, "folded", |_| {});
    assert_eq!(report.folded_neighbours, folded);
    assert!(
        report
            .defects
            .iter()
            .any(|d| d.contains("folded onto a neighbour")),
        "{:?}",
        report.defects
    );
}

/// Two flat sheets 0.2 apart: the smallest gap between layers is that, and none is found
/// within a shorter reach.
#[test]
fn the_smallest_layer_gap_is_measured() {
    let sheets = shapes::stacked_sheets(2, 6, 6, 0.1, 0.2);
    let gap = slayer::collide::smallest_layer_gap(&sheets, 0.3).unwrap();
    assert!(gap.is_some_and(|g| (g - 0.2).abs() < 1e-6), "{gap:?}");
    assert_eq!(
        slayer::collide::smallest_layer_gap(&sheets, 0.1).unwrap(),
        None
    );
    let one = shapes::stacked_sheets(1, 6, 6, 0.1, 0.2);
    assert_eq!(
        slayer::collide::smallest_layer_gap(&one, 0.3).unwrap(),
        None
    );
}

/// On generated plaster (three layers, bumpy, some of its layers near each other), the grid's
/// gap is the all-pairs minimum over every vertex and every face of another layer, bit for bit.
#[test]
fn the_smallest_layer_gap_matches_all_pairs() {
    use slayer::geom::point_triangle_distance_squared;
    use slayer::scene::{SceneKind, SceneSpec, generate};
    let mesh = generate(&SceneSpec {
        kind: SceneKind::Plaster,
        triangles: 3_000,
        seed: 4,
    })
    .unwrap();
    let l = mesh.mean_edge_length();
    for reach in [1.0 * l, 3.0 * l, 8.0 * l] {
        let mut nearest: Option<f32> = None;
        for v in 0..mesh.vertex_count() {
            let p = mesh.positions()[v];
            for f in 0..mesh.face_count() {
                if mesh.face_layers()[f] == mesh.vertex_layers()[v] {
                    continue;
                }
                let [a, b, c] = mesh.face_positions(f);
                let d2 = point_triangle_distance_squared(p, a, b, c);
                if d2 <= reach * reach {
                    nearest = Some(nearest.map_or(d2, |n: f32| n.min(d2)));
                }
            }
        }
        let expected = nearest.map(f32::sqrt).filter(|&g| g <= reach);
        let gap = slayer::collide::smallest_layer_gap(&mesh, reach).unwrap();
        assert_eq!(gap, expected, "reach {reach}");
        if reach > 4.0 * l {
            assert!(
                gap.is_some(),
                "the layers are within 8 L of each other somewhere"
            );
        }
    }
}

/// `check --against` counts the faces turned over since the original (their normal points
/// against the original's): none for the original itself, some once a vertex is pulled
/// across the faces around it.
#[test]
fn faces_turned_over_are_counted_against_the_original() {
    let original = shapes::stacked_sheets(1, 4, 4, 1.0, 0.0);
    let notes = slayer::io::ImportReport::default();
    let mut same = slayer::check::check_mesh(&original, &notes, "same", |_| {});
    same.compare_with(&original, &original);
    assert_eq!(same.turned_over_faces, Some(0));
    let mut folded = original.clone();
    // Vertex (1, 1) pulled past (2, 2): the faces it shares with its lower-left neighbours
    // turn over.
    folded.positions_mut()[6] = Vec3::new(2.5, 2.5, 0.0);
    let turned = slayer::check::turned_over_faces(&folded, &original);
    assert!(turned > 0, "{turned}");
    let mut report = slayer::check::check_mesh(&folded, &notes, "folded", |_| {});
    report.compare_with(&folded, &original);
    assert_eq!(report.turned_over_faces, Some(turned));
    assert!(report.to_string().contains("turned over"), "{report}");
}
