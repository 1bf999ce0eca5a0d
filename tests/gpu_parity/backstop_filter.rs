//! The backstop's f32 filter against its mirror, and conservative: every crossing the exact
//! predicates find is among its pairs.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slayer::gpu::table_size_for;

use crate::common::{ProximityScene, gpu, mesh_table, packed, pressed_sheets, shuffled};

/// A step for the backstop filter: `scene`'s mesh at the step's start, with `order` moved to
/// `targets` unclamped, so that faces cross, turn over and fold onto their neighbours.
fn rough_step(name: &'static str, depth: f32, jitter: f32, seed: u64) -> ProximityScene {
    let mesh = slayer::scene::shapes::stacked_sheets(2, 36, 28, 0.1, 0.06);
    let upper: Vec<u32> = (0..mesh.vertex_count() as u32)
        .filter(|&v| mesh.vertex_layers()[v as usize] == 1)
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut targets = mesh.positions().to_vec();
    for &v in &upper {
        let mut shake = || rng.random_range(-jitter..=jitter);
        targets[v as usize] += Vec3::new(shake(), shake(), shake() - depth);
    }
    ProximityScene {
        name,
        order: shuffled(upper, seed + 1),
        mesh,
        targets,
        edge: 0.1,
    }
}

/// The crossings phase B of `collide` must find, by brute force over every face pair with
/// the CPU's exact predicates: `(f, f)` for a moved face that turned over, `(f, g)` (f < g
/// where both moved) for faces that overlap beyond a shared vertex or cross.
fn reference_crossings(
    mesh: &slayer::mesh::Mesh,
    current: &[Vec3],
    moved: &[bool],
) -> Vec<(u32, u32)> {
    use slayer::geom::{Aabb, neighbours_overlap, triangles_intersect};
    let faces = mesh.faces();
    let corners = |f: usize, at: &[Vec3]| faces[f].map(|v| at[v as usize]);
    let moving = |f: usize| faces[f].iter().any(|&v| moved[v as usize]);
    let boxes: Vec<Aabb> = (0..faces.len())
        .map(|f| Aabb::of_points(&corners(f, current)))
        .collect();
    let mut found = Vec::new();
    for f in (0..faces.len()).filter(|&f| moving(f)) {
        let (before, now) = (corners(f, mesh.positions()), corners(f, current));
        let normal = |t: [Vec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]);
        if normal(before).dot(normal(now)) <= 0.0 && normal(before) != Vec3::ZERO {
            found.push((f as u32, f as u32));
        }
        for g in 0..faces.len() {
            if g == f || (g < f && moving(g)) || !boxes[f].overlaps(&boxes[g]) {
                continue;
            }
            let shares = faces[g].iter().any(|v| faces[f].contains(v));
            let (a, b) = (now, corners(g, current));
            let crosses = if shares {
                neighbours_overlap(a, faces[f], b, faces[g])
            } else {
                triangles_intersect(a, b)
            };
            if crosses {
                found.push((f as u32, g as u32));
            }
        }
    }
    found
}

#[test]
fn backstop_filter_matches_cpu_mirror_and_keeps_every_crossing() {
    let gpu = gpu();
    for scene in [
        rough_step("pierced sheets", 0.09, 0.015, 81),
        rough_step("crumpled sheets", 0.0, 0.05, 83),
        pressed_sheets(),
    ] {
        let all = scene.order.len();
        let mut crossings_seen = 0;
        for size in [0, 1, 63, 64, 65, all] {
            let label = format!("{} at size {size}", scene.name);
            let mut selection = scene.order[..size.min(all)].to_vec();
            selection.sort_unstable();
            let mut current = scene.mesh.positions().to_vec();
            for &v in &selection {
                current[v as usize] = scene.targets[v as usize];
            }
            let query = slayer::gpu::BackstopQuery {
                mesh: &scene.mesh,
                current: &current,
                selection: &selection,
                max_edge: scene.mesh.longest_edge(),
                cell_size: scene.edge,
                capacity: 1 << 16,
            };
            let actual = slayer::gpu::run_backstop_filter(&gpu, &query).expect("GPU run");

            let mesh = &scene.mesh;
            let (moving, moved) = slayer::gpu::backstop_inputs(&query);
            let topology = slayer::gpu::PackedTopology::of(mesh);
            let table_size = table_size_for(mesh.vertex_count());
            let params = slayer::gpu::backstop_query_params(
                &query,
                topology.layout.vertex_rows_base,
                table_size,
            );
            let table = mesh_table(mesh, params.inv_cell_size, table_size);
            let flat = packed(&current);
            let mut mirror = slayer::cpu::backstop_filter(
                &params,
                &slayer::cpu::BackstopInputs {
                    positions: &flat,
                    offsets: &table.offsets,
                    entries: &table.entries,
                    topology: &topology.words,
                    moving: &moving,
                    moved: &moved,
                    overlay_marks: &[],
                    overlay_offsets: &[],
                    overlay_entries: &[],
                },
            );
            assert_eq!(actual.count as usize, mirror.len(), "{label}: pair count");
            let mut pairs = actual.pairs.clone();
            pairs.sort_unstable();
            mirror.sort_unstable();
            assert_eq!(pairs, mirror, "{label}: pairs (GPU vs mirror)");

            // Conservative: every crossing the exact predicates find is among the pairs.
            let moved_flags: Vec<bool> = moved.iter().map(|&m| m != 0).collect();
            let reference = reference_crossings(mesh, &current, &moved_flags);
            for &(f, g) in &reference {
                assert!(
                    pairs.binary_search(&[f, g]).is_ok(),
                    "{label}: crossing ({f}, {g}) not among the {} undecided pairs",
                    pairs.len()
                );
            }
            crossings_seen += reference.len();
            if size == all {
                eprintln!(
                    "backstop, {label}: {} undecided pairs for {} crossings",
                    pairs.len(),
                    reference.len()
                );
            }
        }
        if scene.name != "pressed sheets" {
            assert!(crossings_seen > 0, "{}: the step crosses faces", scene.name);
        }
    }
}
