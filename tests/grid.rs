//! The spatial hash against brute force: random point sets with random inserts, moves and
//! removals, and random meshes for the face queries and picking. Result sets must be identical.

use glam::{Vec2, Vec3};
use proptest::prelude::*;
use slayer::collide::LocalFaceGrid;
use slayer::geom::{Aabb, Ray, point_triangle_distance_squared, ray_triangle};
use slayer::grid::SpatialHash;
use slayer::mesh::Mesh;
use slayer::scene::shapes;

fn vec3(range: f32) -> impl Strategy<Value = Vec3> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

#[derive(Debug, Clone)]
enum Edit {
    Move(usize, Vec3),
    Remove(usize),
    Insert(usize, Vec3),
}

fn edit(points: usize) -> impl Strategy<Value = Edit> {
    prop_oneof![
        (0..points, vec3(5.0)).prop_map(|(i, p)| Edit::Move(i, p)),
        (0..points).prop_map(Edit::Remove),
        (0..points, vec3(5.0)).prop_map(|(i, p)| Edit::Insert(i, p)),
    ]
}

fn brute_sphere(positions: &[Vec3], present: &[bool], center: Vec3, radius: f32) -> Vec<u32> {
    (0..positions.len() as u32)
        .filter(|&v| {
            present[v as usize] && positions[v as usize].distance_squared(center) <= radius * radius
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn sphere_queries_match_brute_force_after_random_edits(
        points in prop::collection::vec(vec3(5.0), 1..300),
        edits in prop::collection::vec(edit(300), 0..200),
        queries in prop::collection::vec((vec3(6.0), 0.0f32..4.0), 1..20),
        cell in 0.05f32..2.0,
    ) {
        let mut positions = points.clone();
        let n = positions.len();
        let mut present = vec![true; n];
        let mut grid = SpatialHash::new(cell, n).unwrap();
        for (v, p) in positions.iter().enumerate() {
            grid.insert(v as u32, *p);
        }
        for e in edits {
            match e {
                Edit::Move(i, p) if i < n => {
                    positions[i] = p;
                    if present[i] { grid.move_to(i as u32, p); }
                }
                Edit::Remove(i) if i < n => {
                    present[i] = false;
                    grid.remove(i as u32);
                }
                Edit::Insert(i, p) if i < n => {
                    positions[i] = p;
                    present[i] = true;
                    grid.insert(i as u32, p);
                }
                _ => {}
            }
        }
        prop_assert_eq!(grid.len(), present.iter().filter(|&&p| p).count());
        grid.check_consistency(&positions).map_err(TestCaseError::fail)?;
        for (center, radius) in queries {
            let mut found = Vec::new();
            grid.vertices_in_sphere(&positions, center, radius, &mut found);
            found.sort_unstable();
            prop_assert_eq!(found, brute_sphere(&positions, &present, center, radius));
        }
    }
}

/// A bumpy sheet and a sphere, with random displacement: real meshes with uneven edges.
fn random_mesh(seed: u64, jitter: f32) -> Mesh {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let (mut positions, mut faces) = shapes::grid_patch(12, 9, 0.1, 0.0, Vec2::ZERO);
    let sphere = slayer::scene::geodesic_sphere(4, 0.4).unwrap();
    let base = positions.len() as u32;
    positions.extend(
        sphere
            .positions()
            .iter()
            .map(|p| *p + Vec3::new(0.6, 0.45, 0.3)),
    );
    faces.extend(sphere.faces().iter().map(|t| t.map(|v| v + base)));
    let mut layers = vec![0; faces.len()];
    for l in layers.iter_mut().skip(12 * 9 * 2) {
        *l = 1;
    }
    for p in &mut positions {
        *p += Vec3::new(
            rng.random_range(-jitter..jitter),
            rng.random_range(-jitter..jitter),
            rng.random_range(-jitter..jitter),
        );
    }
    Mesh::new(
        positions,
        faces,
        layers,
        vec!["sheet".into(), "ball".into()],
    )
    .unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn faces_within_match_brute_force(
        seed in 0u64..1000,
        jitter in 0.0f32..0.05,
        cell_scale in 0.5f32..2.0,
        queries in prop::collection::vec((vec3(1.2), 0.0f32..0.4), 1..16),
    ) {
        let mesh = random_mesh(seed, jitter);
        let stats = mesh.edge_length_stats();
        let grid = SpatialHash::build(&mesh, stats.mean as f32 * cell_scale).unwrap();
        let csr = mesh.vertex_faces();
        let max_edge = stats.max as f32;
        for (point, radius) in queries {
            let point = point + Vec3::new(0.6, 0.45, 0.0);
            let mut found = grid.faces_within(mesh.positions(), mesh.faces(), &csr, point, radius, max_edge);
            found.sort_unstable();
            let brute: Vec<u32> = (0..mesh.face_count() as u32)
                .filter(|&f| {
                    let [a, b, c] = mesh.face_positions(f as usize);
                    point_triangle_distance_squared(point, a, b, c) <= radius * radius
                })
                .collect();
            prop_assert_eq!(found, brute);
        }
    }

    #[test]
    fn first_hit_matches_brute_force(
        seed in 0u64..1000,
        jitter in 0.0f32..0.05,
        cell_scale in 0.5f32..2.0,
        rays in prop::collection::vec((vec3(2.0), vec3(1.0)), 1..16),
    ) {
        let mesh = random_mesh(seed, jitter);
        let stats = mesh.edge_length_stats();
        let grid = SpatialHash::build(&mesh, stats.mean as f32 * cell_scale).unwrap();
        let csr = mesh.vertex_faces();
        for (origin, direction) in rays {
            let ray = Ray { origin: origin + Vec3::new(0.6, 0.45, 0.0), direction };
            let hit = grid.first_hit(mesh.positions(), mesh.faces(), &csr, &ray, stats.max as f32);
            let mut brute: Option<(f32, u32)> = None;
            for f in 0..mesh.face_count() as u32 {
                let [a, b, c] = mesh.face_positions(f as usize);
                if let Some(t) = ray_triangle(&ray, a, b, c)
                    && brute.is_none_or(|(bt, bf)| t < bt || (t == bt && f < bf)) {
                        brute = Some((t, f));
                    }
            }
            prop_assert_eq!(hit.map(|h| (h.t, h.face)), brute);
        }
    }
}

#[test]
fn candidate_faces_are_unique_and_cover_the_neighbourhood() {
    let mesh = shapes::stacked_sheets(2, 10, 10, 1.0, 2.5);
    let grid = SpatialHash::build(&mesh, 1.0).unwrap();
    let csr = mesh.vertex_faces();
    let mut candidates = Vec::new();
    grid.candidate_faces(&csr, Vec3::new(5.0, 5.0, 1.2), 1.5, 1.5, &mut candidates);
    let mut sorted = candidates.clone();
    sorted.dedup();
    assert_eq!(sorted, candidates, "sorted and unique");
    // Both sheets are within reach of a point between them.
    let layers: std::collections::BTreeSet<u32> = candidates
        .iter()
        .map(|&f| mesh.face_layers()[f as usize])
        .collect();
    assert_eq!(layers.len(), 2);
}

#[test]
fn invalid_cell_sizes_are_errors_not_panics() {
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY, 1e-45] {
        assert!(SpatialHash::new(bad, 4).is_err(), "cell size {bad}");
    }
}

#[test]
fn picking_from_above_hits_the_top_layer() {
    let mesh = shapes::stacked_sheets(3, 8, 8, 1.0, 2.0);
    let grid = SpatialHash::build(&mesh, 1.0).unwrap();
    let csr = mesh.vertex_faces();
    let ray = Ray {
        origin: Vec3::new(3.3, 4.6, 50.0),
        direction: -Vec3::Z,
    };
    let hit = grid
        .first_hit(mesh.positions(), mesh.faces(), &csr, &ray, 1.5)
        .expect("hit");
    assert_eq!(mesh.face_layers()[hit.face as usize], 2);
    assert!((hit.point.z - 4.0).abs() < 1e-5);
    let miss = Ray {
        origin: Vec3::new(30.0, 4.6, 50.0),
        direction: -Vec3::Z,
    };
    assert!(
        grid.first_hit(mesh.positions(), mesh.faces(), &csr, &miss, 1.5)
            .is_none()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// The dense grid's one-visit walk meets each face filed near a query once: the faces
    /// every cell the query covers holds, less repeats.
    #[test]
    fn each_face_near_a_query_is_met_once(
        boxes in prop::collection::vec((vec3(4.0), vec3(1.0)), 1..60),
        query in (vec3(5.0), vec3(2.0)),
        cell in 0.2f32..2.0,
    ) {
        let boxes: Vec<Aabb> = boxes
            .iter()
            .map(|&(at, size)| Aabb::of_points(&[at, at + size.abs()]))
            .collect();
        let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.including_box(b));
        let mut grid = LocalFaceGrid::default();
        grid.build(&boxes, bounds, cell);
        let query = Aabb::of_points(&[query.0, query.0 + query.1.abs()]);
        let mut every = Vec::new();
        grid.for_each_candidate(&query, |f| every.push(f));
        every.sort_unstable();
        every.dedup();
        let mut once = Vec::new();
        grid.for_each_face_once(&query, &boxes, |f| once.push(f));
        let met = once.len();
        once.sort_unstable();
        once.dedup();
        prop_assert_eq!(met, once.len(), "a face met twice");
        prop_assert_eq!(once, every);
    }
}

/// Every vertex filed in a cell of the box `[lo, hi]` clipped to the grid's bounds, walking
/// every cell (z, then y, then x); or, where the box has more than four cells per vertex
/// slot, every filed vertex in it in index order: what `for_each_in_box` must give, in this
/// order.
fn walk_every_cell(grid: &SpatialHash, slots: usize, lo: Vec3, hi: Vec3) -> Vec<u32> {
    let bounds = grid.bounds();
    let a = grid.cell_of_point(lo).max(grid.cell_of_point(bounds.min));
    let b = grid.cell_of_point(hi).min(grid.cell_of_point(bounds.max));
    if a.cmpgt(b).any() {
        return Vec::new();
    }
    let cells = (b - a + glam::IVec3::ONE).as_i64vec3();
    if cells.x * cells.y * cells.z > 4 * slots as i64 {
        let inside = |v: u32| {
            grid.cell_of_vertex(v)
                .is_some_and(|c| c.cmpge(a).all() && c.cmple(b).all())
        };
        return (0..slots as u32).filter(|&v| inside(v)).collect();
    }
    let mut found = Vec::new();
    for z in a.z..=b.z {
        for y in a.y..=b.y {
            for x in a.x..=b.x {
                found.extend(grid.cell_vertices(glam::IVec3::new(x, y, z)));
            }
        }
    }
    found
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Box queries skip the cells no vertex is filed in (the grid's occupancy) and meet the
    /// others in the order a walk over every cell does, on a grid built whole and then edited:
    /// the order callers see must not depend on which cells are empty.
    #[test]
    fn box_queries_meet_the_vertices_a_walk_over_every_cell_meets_in_its_order(
        seed in 0u64..1000,
        moves in prop::collection::vec((0usize..400, vec3(0.8)), 0..120),
        boxes in prop::collection::vec((vec3(1.5), vec3(1.2)), 1..12),
        cell in 0.03f32..0.4,
    ) {
        let mesh = random_mesh(seed, 0.02);
        let mut positions = mesh.positions().to_vec();
        let mut grid = SpatialHash::build(&mesh, cell).unwrap();
        grid.check_consistency(&positions).map_err(TestCaseError::fail)?;
        for (i, p) in moves {
            let v = i % positions.len();
            positions[v] = p;
            grid.move_to(v as u32, p);
        }
        grid.check_consistency(&positions).map_err(TestCaseError::fail)?;
        for (at, size) in boxes {
            let (lo, hi) = (at, at + size.abs());
            let mut found = Vec::new();
            grid.for_each_in_box(lo, hi, |v| found.push(v));
            prop_assert_eq!(found, walk_every_cell(&grid, positions.len(), lo, hi));
        }
    }
}
