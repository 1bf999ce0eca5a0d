//! `select` against its mirror (through the hash table, with and without an overlay, after
//! drift) and against the CPU pipeline's selection.

use glam::Vec3;
use slayer::brush::{Brush, BrushKind, Dab, DabFrame, Falloff};
use slayer::gpu::{BrushSphere, SelectedVertex, run_select, select_params, table_size_for};
use slayer::grid::SpatialHash;
use slayer::mesh::VertexFlags;

use crate::common::{FALLOFFS, SIZES, flag_bits, gpu, random_positions, random_vertices};

/// Vertices within this share of the radius of the rim may be in one selection and not the
/// other: `|p − c|² ≤ r²` and `t < 1` are decided on rounded values, and GPUs may fuse the
/// multiply-adds of the dot product. Seeded inputs put none there; the allowance keeps the test
/// about real disagreements.
const RIM_TOLERANCE: f32 = 1e-5;
/// Largest weight difference: `sqrt(1 − t²)` near the rim turns one ulp of `t` into ~1e-6.
const WEIGHT_TOLERANCE: f32 = 1e-5;

/// Compares two selections as sets of vertices, with weights within `WEIGHT_TOLERANCE`;
/// returns the largest weight difference.
fn assert_same_selection(
    label: &str,
    actual: &[(u32, f32)],
    expected: &[(u32, f32)],
    positions: &[Vec3],
    brush: &BrushSphere,
) -> f32 {
    let sorted = |s: &[(u32, f32)]| {
        let mut s = s.to_vec();
        s.sort_by_key(|&(v, _)| v);
        s
    };
    let (actual, expected) = (sorted(actual), sorted(expected));
    for list in [&actual, &expected] {
        if let Some(pair) = list.windows(2).find(|pair| pair[0].0 == pair[1].0) {
            panic!("{label}: vertex {} listed twice: {pair:?}", pair[0].0);
        }
    }
    let reach = |v: u32| positions[v as usize].distance(brush.center) / brush.radius;
    let on_rim = |v: u32| (reach(v) - 1.0).abs() <= RIM_TOLERANCE;
    let (mut i, mut j, mut worst) = (0, 0, 0.0f32);
    while i < actual.len() || j < expected.len() {
        let a = actual.get(i).copied();
        let e = expected.get(j).copied();
        match (a, e) {
            (Some((va, wa)), Some((ve, we))) if va == ve => {
                worst = worst.max((wa - we).abs());
                assert!(
                    (wa - we).abs() <= WEIGHT_TOLERANCE,
                    "{label}: vertex {va} weighs {wa} here, {we} in the reference"
                );
                i += 1;
                j += 1;
            }
            (Some((va, _)), e) if e.is_none_or(|(ve, _)| va < ve) => {
                assert!(
                    on_rim(va),
                    "{label}: vertex {va} selected, not in the reference (at {} of the radius)",
                    reach(va)
                );
                eprintln!("{label}: rim vertex {va} only in one selection");
                i += 1;
            }
            (_, Some((ve, _))) => {
                assert!(
                    on_rim(ve),
                    "{label}: vertex {ve} of the reference not selected (at {} of the radius)",
                    reach(ve)
                );
                eprintln!("{label}: rim vertex {ve} only in one selection");
                j += 1;
            }
            _ => unreachable!(),
        }
    }
    worst
}

fn pairs(selection: &[SelectedVertex]) -> Vec<(u32, f32)> {
    selection.iter().map(|s| (s.vertex, s.weight)).collect()
}

/// The CPU mirror of the GPU backend's selection through an overlay: the main table of the
/// `hashed` positions walked leaving `members` out, then the overlay of `members` at
/// `positions` (or, for a brush whose box outnumbers the vertices, one scan).
#[allow(clippy::too_many_arguments)]
fn cpu_select_with_overlay(
    hashed: &[Vec3],
    positions: &[Vec3],
    layers: &[u32],
    flags: &[u32],
    active: &[bool],
    inv_cell_size: f32,
    brush: &BrushSphere,
    members: &[u32],
) -> Vec<SelectedVertex> {
    let table_size = table_size_for(positions.len());
    let main = slayer::cpu::hash_table(hashed, flags, inv_cell_size, table_size);
    let overlay = slayer::gpu::overlay_table(positions, members, inv_cell_size);
    let filing = slayer::gpu::Filing::of(hashed, positions, members);
    let params = select_params(
        brush,
        filing.drift,
        inv_cell_size,
        table_size,
        positions.len(),
        active.len(),
    );
    let active: Vec<u32> = active.iter().map(|&a| a as u32).collect();
    let mut walks = vec![(&main, params.scan_vertices == 0 && !members.is_empty())];
    if params.scan_vertices == 0 && !members.is_empty() {
        walks.push((&overlay, false));
    }
    let mut selected = vec![SelectedVertex::default(); positions.len()];
    let mut count = 0u32;
    for (table, skip_marked) in walks {
        let inputs = slayer::cpu::SelectInputs {
            positions: bytemuck::cast_slice(positions),
            vertex_layers: layers,
            flags,
            active_layers: &active,
            offsets: &table.offsets,
            entries: &table.entries,
            hashed: bytemuck::cast_slice(&filing.filed_at),
            marks: &filing.marks,
        };
        let params = slayer::gpu::SelectParams {
            table_mask: table.table_size() as u32 - 1,
            skip_marked: skip_marked as u32,
            ..params
        };
        slayer::cpu::select(&params, &inputs, &mut selected, &mut count);
    }
    selected.truncate(count as usize);
    selected
}

/// The CPU mirror chain: hash table of the `hashed` positions, then `select` at `positions`.
fn cpu_select(
    hashed: &[Vec3],
    positions: &[Vec3],
    layers: &[u32],
    flags: &[u32],
    active: &[bool],
    inv_cell_size: f32,
    brush: &BrushSphere,
) -> Vec<SelectedVertex> {
    cpu_select_with_overlay(
        hashed,
        positions,
        layers,
        flags,
        active,
        inv_cell_size,
        brush,
        &[],
    )
}

/// A brush of a few cells around the first vertex (or the origin when there is none), so that
/// buckets shared by cells in and out of its box are filtered; the `i`-th falloff.
fn brush_around(positions: &[Vec3], extent: f32, i: usize) -> BrushSphere {
    BrushSphere {
        center: positions.first().copied().unwrap_or(Vec3::ZERO),
        radius: 0.6 * extent + 0.3,
        falloff: FALLOFFS[i % FALLOFFS.len()],
    }
}

/// Vertices remeshing changed are filed in the overlay at their new positions while their
/// entries in the main table stay where they were: selecting through both (the main table
/// leaving the overlay's members out) finds exactly what one fresh table of the current
/// positions finds — no member missed, none found twice — on the GPU and in the mirror.
#[test]
fn select_through_an_overlay_matches_a_fresh_table() {
    let gpu = gpu();
    let active = [true, false, true];
    for (i, &size) in SIZES.iter().enumerate() {
        let cell_size = 0.25f32;
        let extent = 0.5 * cell_size * (size as f32).cbrt().max(1.0);
        let (positions, layers, flags) = random_vertices(size, 700 + 3 * i as u64, extent);
        // A third of the vertices changed since the main table was built: half of them moved
        // by a cell and a half (their stale entries lie in the brush's box too), half by a
        // hair, within their cells (where both tables file them in the same cell).
        let members: Vec<u32> = (0..size as u32).step_by(3).collect();
        let mut stale = positions.clone();
        for &v in &members {
            stale[v as usize] += if v % 2 == 0 {
                Vec3::new(1.5, -1.5, 0.5) * cell_size
            } else {
                Vec3::splat(1e-6)
            };
        }
        let brush = brush_around(&positions, extent, i);
        let inv = 1.0 / cell_size;
        let expected = cpu_select(
            &positions, &positions, &layers, &flags, &active, inv, &brush,
        );
        let mirrored = cpu_select_with_overlay(
            &stale, &positions, &layers, &flags, &active, inv, &brush, &members,
        );
        let actual = slayer::gpu::run_select_with_overlay(
            &gpu,
            &stale,
            (&positions, &layers, &flags),
            &active,
            inv,
            &brush,
            &members,
        )
        .expect("GPU run");
        assert!(
            size < 64 || expected.iter().any(|s| s.vertex % 3 == 0),
            "size {size}: the overlay's members are selected"
        );
        // The mirror walks the tables as the GPU does; both find what a fresh table finds.
        for (found, by) in [(&actual, "GPU"), (&mirrored, "mirror")] {
            assert_same_selection(
                &format!("size {size} with an overlay ({by})"),
                &pairs(found),
                &pairs(&expected),
                &positions,
                &brush,
            );
        }
        assert_same_selection(
            &format!("size {size} with an overlay (GPU vs mirror)"),
            &pairs(&actual),
            &pairs(&mirrored),
            &positions,
            &brush,
        );
    }
}

#[test]
fn select_matches_cpu_mirror_at_awkward_sizes() {
    let gpu = gpu();
    let active = [true, false, true];
    let mut worst = 0.0f32;
    for (i, &size) in SIZES.iter().enumerate() {
        let cell_size = 0.25f32;
        let extent = 0.5 * cell_size * (size as f32).cbrt().max(1.0);
        let (positions, layers, flags) = random_vertices(size, 200 + 3 * i as u64, extent);
        let brush = brush_around(&positions, extent, i);
        let inv = 1.0 / cell_size;
        let expected = cpu_select(
            &positions, &positions, &layers, &flags, &active, inv, &brush,
        );
        let actual = run_select(
            &gpu, &positions, &positions, &layers, &flags, &active, inv, &brush,
        )
        .expect("GPU run");
        assert!(
            size < 64 || !expected.is_empty(),
            "size {size} selects nothing"
        );
        worst = worst.max(assert_same_selection(
            &format!("size {size}"),
            &pairs(&actual),
            &pairs(&expected),
            &positions,
            &brush,
        ));
    }
    eprintln!("select: largest weight difference GPU vs mirror {worst:e}");
}

#[test]
fn select_scans_vertices_for_huge_brushes_and_folds_wide_dispatches() {
    // A brush far larger than the mesh (more cells than vertices: the per-vertex scan), and a
    // small brush over many cells, both with 7 workgroups per dimension.
    let mut gpu = gpu();
    gpu.limits.max_compute_workgroups_per_dimension = 7;
    let active = [true, true, false];
    let (positions, layers, flags) = random_vertices(100_003, 300, 2.0);
    let inv = 8.0;
    for (radius, scans) in [(50.0, true), (1.3, false)] {
        let brush = BrushSphere {
            center: Vec3::new(0.1, -0.2, 0.3),
            radius,
            falloff: Falloff::Smooth,
        };
        let params = select_params(
            &brush,
            0.0,
            inv,
            table_size_for(positions.len()),
            100_003,
            3,
        );
        assert_eq!(params.scan_vertices != 0, scans, "radius {radius}");
        let expected = cpu_select(
            &positions, &positions, &layers, &flags, &active, inv, &brush,
        );
        let actual = run_select(
            &gpu, &positions, &positions, &layers, &flags, &active, inv, &brush,
        )
        .expect("GPU run");
        assert!(expected.len() > 1000);
        assert_same_selection(
            &format!("radius {radius}"),
            &pairs(&actual),
            &pairs(&expected),
            &positions,
            &brush,
        );
    }
}

#[test]
fn select_mirror_matches_the_cpu_pipeline_for_every_falloff() {
    // The mirror against `pipeline::step::select` (the CPU backend) on a mesh with masked and
    // partly masked vertices and an inactive layer; GPU against the mirror for the same brushes.
    let gpu = gpu();
    let mut mesh = slayer::scene::shapes::stacked_sheets(3, 40, 30, 0.1, 0.05);
    for v in (0..mesh.vertex_count()).step_by(7) {
        mesh.flags_mut()[v].insert(VertexFlags::MASKED);
    }
    // Partial masks lower the weights: the same product on every side.
    for (k, v) in (3..mesh.vertex_count()).step_by(5).enumerate() {
        mesh.flags_mut()[v].set_mask([0.2, 0.5, 0.9][k % 3]);
    }
    let grid = SpatialHash::build(&mesh, 0.1).unwrap();
    let active = [true, false, true];
    let state = slayer::collide::StrokeState {
        grid: Some(&grid),
        active: &active,
        parallel: false,
        collision_distance: 0.1,
        ring: 2,
        max_edge: 0.15,
        cull: true,
    };
    let flags = flag_bits(&mesh);
    let layers = mesh.vertex_layers().to_vec();
    let mut worst = 0.0f32;
    for (k, &falloff) in FALLOFFS.iter().enumerate() {
        let brush = BrushSphere {
            center: Vec3::new(1.3 + 0.37 * k as f32, 1.1, 0.04),
            radius: 0.55,
            falloff,
        };
        let dab = Dab {
            brush: Brush {
                kind: BrushKind::Draw,
                radius: brush.radius,
                strength: 1.0,
                falloff,
                invert: false,
            },
            frame: DabFrame {
                center: brush.center,
                normal: Vec3::Z,
                plane_point: brush.center,
                motion: Vec3::ZERO,
            },
            pressure: 1.0,
            share: 1.0,
        };
        let reference = slayer::pipeline::step::select(&state, &mesh, &dab);
        assert!(reference.len() > 50);
        let mirror = cpu_select(
            mesh.positions(),
            mesh.positions(),
            &layers,
            &flags,
            &active,
            grid.inv_cell_size(),
            &brush,
        );
        let label = format!("falloff {}", falloff.name());
        worst = worst.max(assert_same_selection(
            &label,
            &pairs(&mirror),
            &reference,
            mesh.positions(),
            &brush,
        ));
        let actual = run_select(
            &gpu,
            mesh.positions(),
            mesh.positions(),
            &layers,
            &flags,
            &active,
            grid.inv_cell_size(),
            &brush,
        )
        .expect("GPU run");
        worst = worst.max(assert_same_selection(
            &label,
            &pairs(&actual),
            &reference,
            mesh.positions(),
            &brush,
        ));
    }
    eprintln!("select: largest weight difference vs the CPU pipeline {worst:e}");
}

#[test]
fn select_finds_vertices_that_moved_since_the_table_was_built() {
    // A backend keeps its table while vertices drift (up to a few cells here): the selection
    // at the current positions must be exactly the brute-force one, on the mirror and the GPU.
    let gpu = gpu();
    let active = [true, false, true];
    let cell_size = 0.25f32;
    let mut worst = 0.0f32;
    for (i, &size) in SIZES.iter().enumerate() {
        let extent = 0.5 * cell_size * (size as f32).cbrt().max(1.0);
        let (hashed, layers, flags) = random_vertices(size, 700 + 3 * i as u64, extent);
        let nudges = random_positions(size, 701 + 3 * i as u64, 1.0);
        // Every third vertex moves, some by up to three cells.
        let positions: Vec<Vec3> = hashed
            .iter()
            .zip(&nudges)
            .enumerate()
            .map(|(v, (p, n))| if v % 3 == 0 { *p + *n * 0.75 } else { *p })
            .collect();
        let brush = BrushSphere {
            center: positions.first().copied().unwrap_or(Vec3::ZERO),
            radius: 0.6 * extent + 0.3,
            falloff: FALLOFFS[i % FALLOFFS.len()],
        };
        let inv = 1.0 / cell_size;
        let brute: Vec<(u32, f32)> = (0..size as u32)
            .filter(|&v| {
                let f = flags[v as usize];
                let l = layers[v as usize] as usize;
                f & (VertexFlags::MASKED | VertexFlags::DEAD).bits() == 0
                    && active[l]
                    && positions[v as usize].distance(brush.center) <= brush.radius
            })
            .map(|v| {
                let t = positions[v as usize].distance(brush.center) / brush.radius;
                (v, brush.falloff.weight(t))
            })
            .filter(|&(_, w)| w > 0.0)
            .collect();
        let expected = cpu_select(&hashed, &positions, &layers, &flags, &active, inv, &brush);
        let actual = run_select(
            &gpu, &hashed, &positions, &layers, &flags, &active, inv, &brush,
        )
        .expect("GPU run");
        let label = format!("size {size}, drifted");
        worst = worst.max(assert_same_selection(
            &label,
            &pairs(&expected),
            &brute,
            &positions,
            &brush,
        ));
        worst = worst.max(assert_same_selection(
            &label,
            &pairs(&actual),
            &pairs(&expected),
            &positions,
            &brush,
        ));
    }
    eprintln!("select after drift: largest weight difference {worst:e}");
}
