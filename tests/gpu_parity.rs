//! Every WGSL kernel against its CPU mirror, on the adapter the machine has (lavapipe in CI).
//! These tests never skip: a machine without any Vulkan adapter fails them, and
//! `tools/test.sh` installs lavapipe so that CI always has one.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slayer::brush::{Brush, BrushKind, Dab, DabFrame, Falloff};
use slayer::gpu::{
    AdapterChoice, BrushSphere, CellKeyParams, CountParams, CsrTable, GpuContext, SelectedVertex,
    deform_params, run_cell_counts, run_cell_keys, run_deform, run_dispatch_args,
    run_exclusive_scan, run_hash_table, run_scatter, run_select, select_params,
    smoothing_neighbours, table_size_for,
};
use slayer::grid::{SpatialHash, cell_coordinates, hash_cell};
use slayer::mesh::{INVALID, Mesh, VertexFlags};

fn gpu() -> GpuContext {
    let gpu = GpuContext::new(AdapterChoice {
        allow_software: true,
    })
    .unwrap_or_else(|e| panic!("GPU tests need an adapter (run tools/test.sh): {e}"));
    eprintln!("GPU tests on: {}", gpu.adapter);
    gpu
}

/// An adapter whose device enforces storage bindings of `bytes` at most, so that the arrays
/// the kernels page (topology, smoothing neighbours) span several bindings.
fn gpu_with_binding_limit(bytes: u64) -> GpuContext {
    let gpu = GpuContext::with_limits(
        AdapterChoice {
            allow_software: true,
        },
        |limits| limits.max_storage_buffer_binding_size = bytes,
    )
    .unwrap_or_else(|e| panic!("GPU tests need an adapter (run tools/test.sh): {e}"));
    assert_eq!(gpu.page_bytes(), bytes, "a power of two is its own page");
    gpu
}

/// The smallest power-of-two binding limit that holds `unpaged` bytes (the largest array bound
/// whole) and each of `paged` in four pages, checked to split the first over two or more.
fn binding_limit_paging(unpaged: u64, paged: &[u64]) -> u64 {
    let largest = paged.iter().copied().max().unwrap_or(0);
    let limit = unpaged
        .max(largest.div_ceil(slayer::gpu::PAGE_COUNT))
        .next_power_of_two()
        .max(256);
    let pages: Vec<u64> = paged.iter().map(|bytes| bytes.div_ceil(limit)).collect();
    assert!(
        pages[0] >= 2,
        "{paged:?} bytes in pages of {limit}: {pages:?} pages"
    );
    eprintln!("binding limit {limit} bytes: {paged:?} bytes paged over {pages:?} bindings");
    limit
}

/// Awkward sizes around the 64-wide workgroup, plus a large odd one.
const SIZES: [usize; 7] = [0, 1, 63, 64, 65, 1000, 512 * 16 + 123];

fn random_positions(count: usize, seed: u64, extent: f32) -> Vec<Vec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            Vec3::new(
                rng.random_range(-extent..extent),
                rng.random_range(-extent..extent),
                rng.random_range(-extent..extent),
            )
        })
        .collect()
}

fn cpu_cell_keys(positions: &[Vec3], inv_cell_size: f32, table_size: u32) -> Vec<u32> {
    let params = CellKeyParams {
        count: positions.len() as u32,
        table_mask: table_size - 1,
        inv_cell_size,
        _pad: 0,
    };
    let flat: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
    let mut keys = vec![0u32; positions.len()];
    slayer::cpu::cell_keys(&params, &flat, &mut keys);
    keys
}

#[test]
fn cell_keys_matches_cpu_mirror_at_awkward_sizes() {
    let gpu = gpu();
    for (i, &size) in SIZES.iter().enumerate() {
        let positions = random_positions(size, 17 + i as u64, 3.0);
        let inv_cell_size = 1.0 / 0.037;
        let table_size = (2 * size).next_power_of_two().max(64) as u32;
        let expected = cpu_cell_keys(&positions, inv_cell_size, table_size);
        let actual = run_cell_keys(&gpu, &positions, inv_cell_size, table_size).expect("GPU run");
        assert_eq!(actual, expected, "cell keys differ at size {size}");
    }
}

#[test]
fn cell_keys_agree_on_cell_boundaries_and_negative_cells() {
    // Points exactly on cell faces, and far negative cells whose bits wrap in the hash.
    let gpu = gpu();
    let cell = 0.25f32;
    let mut positions = Vec::new();
    for k in -40..40 {
        let x = k as f32 * cell;
        positions.push(Vec3::new(x, -x, 0.5 * x));
        positions.push(Vec3::new(x - 1e-7, x + 1e-7, -1000.0 * x));
    }
    let expected = cpu_cell_keys(&positions, 1.0 / cell, 1 << 20);
    let actual = run_cell_keys(&gpu, &positions, 1.0 / cell, 1 << 20).expect("GPU run");
    assert_eq!(actual, expected);
}

#[test]
fn cell_keys_mirror_matches_the_grid_hash() {
    // The mirror is the grid's own cell arithmetic, so GPU tables agree with the CPU grid.
    let positions = random_positions(500, 5, 10.0);
    let inv = 1.0 / 0.3;
    let keys = cpu_cell_keys(&positions, inv, 1024);
    for (p, k) in positions.iter().zip(keys) {
        let cell = slayer::grid::cell_coordinates(*p, inv);
        assert_eq!(k, slayer::grid::hash_cell(cell, 1024));
    }
}

#[test]
fn wide_dispatches_fold_into_two_dimensions() {
    // Pretend the adapter allows only 7 workgroups per dimension, so 100003 invocations fold
    // into y and every kernel's `flat_index` path runs.
    let mut gpu = gpu();
    gpu.limits.max_compute_workgroups_per_dimension = 7;
    let positions = random_positions(100_003, 99, 2.0);
    let (x, y) = gpu.dispatch_size(positions.len(), 64);
    assert_eq!(x, 7);
    assert!(x as usize * y as usize * 64 >= positions.len());
    let expected = cpu_cell_keys(&positions, 8.0, 1 << 18);
    let actual = run_cell_keys(&gpu, &positions, 8.0, 1 << 18).expect("GPU run");
    assert_eq!(actual, expected);
}

/// Scan sizes: empty, one, one block ± 1, past a block of blocks (three levels), large odd.
const SCAN_SIZES: [usize; 7] = [0, 1, 255, 256, 257, 65_537, 300_001];

fn random_u32s(count: usize, seed: u64, below: u32) -> Vec<u32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count).map(|_| rng.random_range(0..below)).collect()
}

/// About one vertex in eight dead; dead ones must stay out of every table.
fn random_flags(count: usize, seed: u64) -> Vec<u32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|_| match rng.random_range(0..8) {
            0 => VertexFlags::DEAD.bits(),
            1 => VertexFlags::MASKED.bits(),
            _ => 0,
        })
        .collect()
}

#[test]
fn scan_matches_cpu_mirror_and_a_running_sum() {
    let gpu = gpu();
    for (i, &size) in SCAN_SIZES.iter().enumerate() {
        // Values up to 2^20 make the totals of the large sizes wrap past 2^32, as they may.
        let values = random_u32s(size, 40 + i as u64, if i % 2 == 0 { 9 } else { 1 << 20 });
        let mut running = 0u32;
        let sequential: Vec<u32> = values
            .iter()
            .map(|&v| {
                let before = running;
                running = running.wrapping_add(v);
                before
            })
            .collect();
        let mut mirror = values.clone();
        slayer::cpu::exclusive_scan(&mut mirror);
        assert_eq!(mirror, sequential, "CPU mirror at size {size}");
        let actual = run_exclusive_scan(&gpu, &values).expect("GPU run");
        assert_eq!(actual, sequential, "GPU scan at size {size}");
    }
}

#[test]
fn cell_counts_match_cpu_mirror_and_ranks_number_each_bucket() {
    let gpu = gpu();
    for (i, &size) in SIZES.iter().enumerate() {
        // A small table, so buckets hold many vertices and the atomics contend.
        let table_size = 64u32;
        let keys = random_u32s(size, 60 + i as u64, table_size);
        let flags = random_flags(size, 70 + i as u64);
        let mut counts = vec![0u32; table_size as usize + 1];
        let mut ranks = vec![0u32; size];
        slayer::cpu::cell_counts(
            &CountParams::new(size),
            &keys,
            &flags,
            &mut counts,
            &mut ranks,
        );
        let (gpu_counts, gpu_ranks) =
            run_cell_counts(&gpu, &keys, &flags, table_size).expect("GPU run");
        assert_eq!(gpu_counts, counts, "counts at size {size}");
        // Ranks depend on the order the atomics ran in: per bucket they must be 0..count.
        let mut seen = vec![Vec::new(); table_size as usize];
        for v in 0..size {
            if flags[v] & VertexFlags::DEAD.bits() != 0 {
                assert_eq!(gpu_ranks[v], INVALID, "dead vertex {v} ranked");
            } else {
                seen[keys[v] as usize].push(gpu_ranks[v]);
            }
        }
        for (bucket, mut ranks) in seen.into_iter().enumerate() {
            ranks.sort_unstable();
            let expected: Vec<u32> = (0..counts[bucket]).collect();
            assert_eq!(ranks, expected, "ranks of bucket {bucket} at size {size}");
        }
    }
}

#[test]
fn scatter_matches_cpu_mirror_given_the_same_ranks() {
    // With the ranks fixed, scatter is a permutation: the outputs are identical.
    let gpu = gpu();
    for (i, &size) in SIZES.iter().enumerate() {
        let table_size = 128u32;
        let keys = random_u32s(size, 80 + i as u64, table_size);
        let flags = random_flags(size, 90 + i as u64);
        let params = CountParams::new(size);
        let mut offsets = vec![0u32; table_size as usize + 1];
        let mut ranks = vec![0u32; size];
        slayer::cpu::cell_counts(&params, &keys, &flags, &mut offsets, &mut ranks);
        slayer::cpu::exclusive_scan(&mut offsets);
        let mut entries = vec![0u32; offsets[table_size as usize] as usize];
        slayer::cpu::scatter(&params, &keys, &ranks, &offsets, &mut entries);
        let actual = run_scatter(&gpu, &keys, &ranks, &offsets).expect("GPU run");
        assert_eq!(actual, entries, "entries at size {size}");
    }
}

/// Checks a table against the grid: every occupied cell's vertices, found through the table's
/// bucket and filtered by cell as the GPU queries do, are the grid's vertices of that cell.
fn assert_table_answers_like_the_grid(
    table: &CsrTable,
    grid: &SpatialHash,
    positions: &[Vec3],
    flags: &[u32],
) {
    assert_eq!(table.table_size(), grid.bucket_count());
    let live = flags
        .iter()
        .filter(|&&f| f & VertexFlags::DEAD.bits() == 0)
        .count();
    assert_eq!(table.entries.len(), live, "filed vertices");
    let inv = grid.inv_cell_size();
    for (v, p) in positions.iter().enumerate() {
        let cell = cell_coordinates(*p, inv);
        let mut from_table: Vec<u32> = table
            .bucket(hash_cell(cell, table.table_size() as u32))
            .iter()
            .copied()
            .filter(|&u| cell_coordinates(positions[u as usize], inv) == cell)
            .collect();
        from_table.sort_unstable();
        let mut from_grid: Vec<u32> = grid.cell_vertices(cell).collect();
        from_grid.sort_unstable();
        assert_eq!(from_table, from_grid, "cell {cell} of vertex {v}");
    }
}

fn grid_of(positions: &[Vec3], flags: &[u32], cell_size: f32) -> SpatialHash {
    let mut grid = SpatialHash::new(cell_size, positions.len()).unwrap();
    for (v, p) in positions.iter().enumerate() {
        if flags[v] & VertexFlags::DEAD.bits() == 0 {
            grid.insert(v as u32, *p);
        }
    }
    grid
}

#[test]
fn hash_table_matches_cpu_chain_and_the_grid() {
    let gpu = gpu();
    for (i, &size) in SIZES.iter().enumerate() {
        // About three vertices per occupied cell, so buckets hold several.
        let cell_size = 0.25;
        let extent = 0.5 * cell_size * (size as f32).cbrt().max(1.0);
        let positions = random_positions(size, 100 + i as u64, extent);
        let flags = random_flags(size, 110 + i as u64);
        let grid = grid_of(&positions, &flags, cell_size);
        let inv = grid.inv_cell_size();
        let table_size = table_size_for(size);
        let expected = slayer::cpu::hash_table(&positions, &flags, inv, table_size);
        assert_table_answers_like_the_grid(&expected, &grid, &positions, &flags);
        let actual = run_hash_table(&gpu, &positions, &flags, inv, table_size).expect("GPU run");
        // Offsets are exact; within a bucket the GPU order is the atomics' order.
        assert_eq!(actual.offsets, expected.offsets, "offsets at size {size}");
        assert_eq!(actual.canonical(), expected, "buckets at size {size}");
    }
}

#[test]
fn hash_table_of_stacked_sheets_matches_the_meshs_grid() {
    let gpu = gpu();
    let mesh = slayer::scene::shapes::stacked_sheets(3, 40, 30, 0.1, 0.05);
    let grid = SpatialHash::build(&mesh, 0.1).unwrap();
    let flags: Vec<u32> = mesh.flags().iter().map(|f| f.bits()).collect();
    let table = run_hash_table(
        &gpu,
        mesh.positions(),
        &flags,
        grid.inv_cell_size(),
        grid.bucket_count() as u32,
    )
    .expect("GPU run");
    assert_table_answers_like_the_grid(&table, &grid, mesh.positions(), &flags);
}

#[test]
fn hash_build_folds_wide_dispatches() {
    // 7 workgroups per dimension: every pass of the build, and a three-level scan whose last
    // row of workgroups runs past the final block, folds into y.
    let mut gpu = gpu();
    gpu.limits.max_compute_workgroups_per_dimension = 7;
    let values = random_u32s(300_001, 7, 5);
    let mut expected = values.clone();
    slayer::cpu::exclusive_scan(&mut expected);
    assert_eq!(
        run_exclusive_scan(&gpu, &values).expect("GPU run"),
        expected
    );
    let positions = random_positions(100_003, 8, 2.0);
    let flags = random_flags(positions.len(), 9);
    let table_size = table_size_for(positions.len());
    let expected = slayer::cpu::hash_table(&positions, &flags, 10.0, table_size);
    let actual = run_hash_table(&gpu, &positions, &flags, 10.0, table_size).expect("GPU run");
    assert_eq!(actual.canonical(), expected);
}

const FALLOFFS: [Falloff; 5] = [
    Falloff::Blend { n: 3 },
    Falloff::Blend { n: 6 },
    Falloff::Smooth,
    Falloff::Sphere,
    Falloff::Linear,
];

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
    let on_rim = |v: u32| {
        let d = positions[v as usize].distance(brush.center);
        (d - brush.radius).abs() <= RIM_TOLERANCE * brush.radius
    };
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
                    "{label}: vertex {va} selected, not in the reference"
                );
                eprintln!("{label}: rim vertex {va} only in one selection");
                i += 1;
            }
            (_, Some((ve, _))) => {
                assert!(
                    on_rim(ve),
                    "{label}: vertex {ve} of the reference not selected"
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

/// Random vertices on three layers (the middle one inactive), some masked or dead.
fn random_vertices(size: usize, seed: u64, extent: f32) -> (Vec<Vec3>, Vec<u32>, Vec<u32>) {
    let positions = random_positions(size, seed, extent);
    let layers = random_u32s(size, seed + 1, 3);
    let flags = random_flags(size, seed + 2);
    (positions, layers, flags)
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
    // The mirror against `pipeline::step::select` (the CPU backend) on a mesh with masked
    // vertices and an inactive layer; GPU against the mirror for the same brushes.
    let gpu = gpu();
    let mut mesh = slayer::scene::shapes::stacked_sheets(3, 40, 30, 0.1, 0.05);
    for v in (0..mesh.vertex_count()).step_by(7) {
        mesh.flags_mut()[v].insert(VertexFlags::MASKED);
    }
    let grid = SpatialHash::build(&mesh, 0.1).unwrap();
    let active = [true, false, true];
    let state = slayer::pipeline::step::StrokeState {
        grid: Some(&grid),
        active: &active,
        parallel: false,
        collision_distance: 0.1,
        ring: 2,
        max_edge: 0.15,
    };
    let flags: Vec<u32> = mesh.flags().iter().map(|f| f.bits()).collect();
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

/// Deformation targets may differ by this share of the brush radius: the shader's sin/cos,
/// sqrt and fused multiply-adds round differently from the CPU's.
const DEFORM_TOLERANCE: f32 = 1e-5;

/// Stacked sheets with bumpy heights and matching normals, masked here and there, so that
/// every field (smooth, flatten, inflate) has something to do.
fn bumpy_sheets() -> slayer::mesh::Mesh {
    let mut mesh = slayer::scene::shapes::stacked_sheets(3, 120, 100, 0.05, 0.2);
    let mut rng = ChaCha8Rng::seed_from_u64(500);
    for p in mesh.positions_mut() {
        p.z += 0.01 * (3.0 * p.x).sin() * (2.0 * p.y).cos() + rng.random_range(-0.004..0.004);
    }
    mesh.recompute_normals();
    for v in (0..mesh.vertex_count()).step_by(11) {
        mesh.flags_mut()[v].insert(VertexFlags::MASKED);
    }
    mesh
}

/// Largest distance between corresponding targets, over the radius.
fn worst_relative(a: &[Vec3], b: &[Vec3], radius: f32) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q) / radius)
        .fold(0.0, f32::max)
}

#[test]
fn deform_matches_cpu_mirror_and_the_brush_fields() {
    check_deform(Binding::Whole);
}

#[test]
fn deform_reads_neighbours_split_over_several_bindings() {
    check_deform(Binding::Paged);
}

fn check_deform(binding: Binding) {
    // Every deforming brush, alternately inverted, over the falloffs; each on the full
    // selection (a large odd size) and on a prefix of an awkward size. The mirror is checked
    // against `pipeline::step::deform` (src/brush/field.rs), the GPU against the mirror.
    let mesh = bumpy_sheets();
    let mut gpu = match binding {
        Binding::Whole => gpu(),
        Binding::Paged => {
            // Whole: positions, normals and targets, 12 bytes a vertex at most.
            let unpaged = 12 * mesh.vertex_count() as u64;
            let neighbours = smoothing_neighbours(&mesh, 0).words.len() as u64 * 4;
            gpu_with_binding_limit(binding_limit_paging(unpaged, &[neighbours]))
        }
    };
    let grid = SpatialHash::build(&mesh, 0.05).unwrap();
    let active = [true, false, true];
    let state = slayer::pipeline::step::StrokeState {
        grid: Some(&grid),
        active: &active,
        parallel: false,
        collision_distance: 0.05,
        ring: 2,
        max_edge: 0.08,
    };
    let neighbours = smoothing_neighbours(&mesh, 0);
    let (mut worst_mirror, mut worst_gpu) = (0.0f32, 0.0f32);
    for (k, &kind) in BrushKind::DEFORMING.iter().enumerate() {
        let falloff = FALLOFFS[k % FALLOFFS.len()];
        let center = Vec3::new(3.0, 2.5, 0.2);
        let dab = Dab {
            brush: Brush {
                kind,
                radius: 2.2,
                strength: 0.8,
                falloff,
                invert: k % 2 == 1,
            },
            frame: DabFrame {
                center,
                normal: Vec3::new(0.1, -0.2, 1.0).normalize(),
                plane_point: center - Vec3::new(0.0, 0.0, 0.15),
                motion: Vec3::new(0.03, -0.02, 0.04),
            },
            pressure: 0.9,
            share: 0.5,
        };
        let full = slayer::pipeline::step::select(&state, &mesh, &dab);
        assert!(full.len() > 8315, "{} selects {}", kind.name(), full.len());
        // The last round folds the dispatch into two dimensions.
        if k == BrushKind::DEFORMING.len() - 1 {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        for size in [8315, SIZES[k % SIZES.len()]] {
            let selection = &full[..size];
            let reference = slayer::pipeline::step::deform(&state, &mesh, &dab, selection);
            let entries: Vec<SelectedVertex> = selection
                .iter()
                .map(|&(vertex, weight)| SelectedVertex { vertex, weight })
                .collect();
            let params = deform_params(&dab, entries.len());
            let inputs = slayer::cpu::DeformInputs {
                positions: mesh.positions(),
                normals: mesh.normals(),
                selected: &entries,
                selection_count: entries.len() as u32,
                neighbour_rows: &neighbours.rows.table,
                neighbours: &neighbours.words,
                frame_sums: &[0; slayer::cpu::FRAME_SUM_WORDS],
            };
            let mut mirror = vec![Vec3::ZERO; entries.len()];
            slayer::cpu::deform(&params, &inputs, &mut mirror);
            let actual = run_deform(&gpu, &mesh, &dab, &entries).expect("GPU run");
            let (m, g) = (
                worst_relative(&mirror, &reference, dab.brush.radius),
                worst_relative(&actual, &mirror, dab.brush.radius),
            );
            let label = format!("{} ({}) at size {size}", kind.name(), falloff.name());
            assert!(
                m <= DEFORM_TOLERANCE,
                "{label}: mirror off the field by {m:e} radii"
            );
            assert!(
                g <= DEFORM_TOLERANCE,
                "{label}: GPU off the mirror by {g:e} radii"
            );
            // A prefix may hold only rim vertices whose weight rounds their move away.
            if size == 8315 {
                let moved = mirror
                    .iter()
                    .zip(selection)
                    .any(|(q, &(v, _))| *q != mesh.positions()[v as usize]);
                assert!(moved, "{label}: nothing moved");
            }
            worst_mirror = worst_mirror.max(m);
            worst_gpu = worst_gpu.max(g);
        }
    }
    eprintln!(
        "deform: largest deviation mirror vs field {worst_mirror:e}, GPU vs mirror {worst_gpu:e} (× radius)"
    );
}

/// A selection of `mesh` under a brush at `center`, as (vertex, weight) in vertex order.
fn selection_under(mesh: &slayer::mesh::Mesh, center: Vec3, radius: f32) -> Vec<SelectedVertex> {
    mesh.positions()
        .iter()
        .enumerate()
        .filter_map(|(v, p)| {
            let t = p.distance(center) / radius;
            (t < 1.0).then(|| SelectedVertex {
                vertex: v as u32,
                weight: Falloff::Smooth.weight(t),
            })
        })
        .collect()
}

#[test]
fn brush_frame_sums_match_the_cpu_mirror_bit_for_bit_in_any_order() {
    // The sums are integers: the GPU's (workgroup partials, then atomics in whatever order the
    // workgroups ran) equal the mirror's exactly, for every awkward size and for the list in
    // any order. The frame they give is the weighted mean normal and centroid (checked in f64).
    let mesh = bumpy_sheets();
    let mut gpu = gpu();
    let (center, radius) = (Vec3::new(3.0, 2.5, 0.1), 2.4);
    let mut full = selection_under(&mesh, center, radius);
    assert!(full.len() > 8315, "selects {}", full.len());
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    for (round, &size) in SIZES.iter().chain(&[full.len()]).enumerate() {
        if round == SIZES.len() {
            // The whole list, its dispatch folded into two dimensions.
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let selection = &mut full[..size];
        let mut mirror = [0u32; slayer::cpu::FRAME_SUM_WORDS];
        let params = slayer::gpu::frame_params(center, radius, size);
        fn inputs<'a>(
            mesh: &'a slayer::mesh::Mesh,
            selected: &'a [SelectedVertex],
        ) -> slayer::cpu::FrameInputs<'a> {
            slayer::cpu::FrameInputs {
                positions: mesh.positions(),
                normals: mesh.normals(),
                selected,
                selection_count: selected.len() as u32,
            }
        }
        slayer::cpu::brush_frame(&params, &inputs(&mesh, selection), &mut mirror);
        let on_gpu = |selection: &[SelectedVertex]| {
            slayer::gpu::run_brush_frame(
                &gpu,
                (mesh.positions(), mesh.normals()),
                selection,
                center,
                radius,
            )
            .expect("GPU run")
        };
        assert_eq!(on_gpu(selection), mirror, "size {size}: GPU vs mirror");
        // Shuffled: the same bits on both.
        for i in (1..selection.len()).rev() {
            selection.swap(i, rng.random_range(0..=i));
        }
        let mut shuffled = [0u32; slayer::cpu::FRAME_SUM_WORDS];
        slayer::cpu::brush_frame(&params, &inputs(&mesh, selection), &mut shuffled);
        assert_eq!(shuffled, mirror, "size {size}: mirror in another order");
        assert_eq!(
            on_gpu(selection),
            mirror,
            "size {size}: GPU in another order"
        );
        selection.sort_unstable_by_key(|s| s.vertex);

        let flags = slayer::cpu::FRAME_NORMAL_FROM_SUMS | slayer::cpu::FRAME_PLANE_FROM_SUMS;
        let (normal, plane) =
            slayer::cpu::frame_from_sums(&mirror, flags, (center, radius), (Vec3::Z, center));
        let (mut n, mut p, mut w) = (glam::DVec3::ZERO, glam::DVec3::ZERO, 0.0f64);
        for s in selection.iter() {
            let weight = s.weight as f64;
            n += mesh.normals()[s.vertex as usize].as_dvec3() * weight;
            p += mesh.positions()[s.vertex as usize].as_dvec3() * weight;
            w += weight;
        }
        let (expected_normal, expected_plane) = if w > 0.0 {
            (n.normalize().as_vec3(), (p / w).as_vec3())
        } else {
            (Vec3::Z, center)
        };
        assert!(
            normal.distance(expected_normal) < 1e-5
                && plane.distance(expected_plane) < 1e-5 * radius,
            "size {size}: frame {normal} {plane}, expected {expected_normal} {expected_plane}"
        );
    }
}

#[test]
fn deform_takes_the_frame_from_the_sums_as_the_mirror_does() {
    // Selection → brush_frame → deform in one submission, as the GPU backend opens a sample:
    // the brushes that read the frame (flatten its plane and normal, draw and twist their
    // normal) move every vertex as the mirror does with the mirror's sums; with the sample's
    // own normal only the plane comes from the sums.
    let mesh = bumpy_sheets();
    let gpu = gpu();
    let neighbours = smoothing_neighbours(&mesh, 0);
    let center = Vec3::new(2.6, 1.9, 0.1);
    let full = selection_under(&mesh, center, 1.7);
    let mut worst = 0.0f32;
    for (k, kind) in [BrushKind::Flatten, BrushKind::Draw, BrushKind::Twist]
        .into_iter()
        .enumerate()
    {
        for own_normal in [None, Some(Vec3::new(0.3, 0.1, 1.0).normalize())] {
            let dab = Dab {
                brush: Brush {
                    kind,
                    radius: 1.7,
                    strength: 0.7,
                    falloff: Falloff::Smooth,
                    invert: k == 1,
                },
                frame: DabFrame {
                    center,
                    normal: own_normal.unwrap_or(Vec3::Z),
                    plane_point: center,
                    motion: Vec3::ZERO,
                },
                pressure: 1.0,
                share: 1.0,
            };
            let flags = slayer::pipeline::step::frame_flags(own_normal);
            for size in [0, 65, full.len()] {
                let selection = &full[..size];
                let (sums, actual) =
                    slayer::gpu::run_framed_deform(&gpu, &mesh, &dab, selection, flags)
                        .expect("GPU run");
                let mut mirror_sums = [0u32; slayer::cpu::FRAME_SUM_WORDS];
                slayer::cpu::brush_frame(
                    &slayer::gpu::frame_params(center, dab.brush.radius, size),
                    &slayer::cpu::FrameInputs {
                        positions: mesh.positions(),
                        normals: mesh.normals(),
                        selected: selection,
                        selection_count: size as u32,
                    },
                    &mut mirror_sums,
                );
                let label = format!("{} at size {size}, own normal {own_normal:?}", kind.name());
                assert_eq!(sums, mirror_sums, "{label}: sums");
                let params = slayer::gpu::DeformParams {
                    frame: flags,
                    ..deform_params(&dab, size)
                };
                let mirror_deform = |params: &slayer::gpu::DeformParams, frame_sums| {
                    let mut targets = vec![Vec3::ZERO; size];
                    let inputs = slayer::cpu::DeformInputs {
                        positions: mesh.positions(),
                        normals: mesh.normals(),
                        selected: selection,
                        selection_count: size as u32,
                        neighbour_rows: &neighbours.rows.table,
                        neighbours: &neighbours.words,
                        frame_sums,
                    };
                    slayer::cpu::deform(params, &inputs, &mut targets);
                    targets
                };
                let mirror = mirror_deform(&params, &mirror_sums);
                let g = worst_relative(&actual, &mirror, dab.brush.radius);
                assert!(
                    g <= DEFORM_TOLERANCE,
                    "{label}: GPU off the mirror by {g:e} radii"
                );
                worst = worst.max(g);
                // The mirror with the frame resolved up front, as the pipeline passes it on to
                // the sample's later steps: the same targets.
                let frame = slayer::pipeline::step::frame_of_sums(&mirror_sums, &dab, own_normal);
                let resolved = deform_params(&Dab { frame, ..dab }, size);
                let again = mirror_deform(&resolved, &[0; slayer::cpu::FRAME_SUM_WORDS]);
                assert_eq!(again, mirror, "{label}: frame resolved up front");
                if size == full.len() {
                    let moved = mirror
                        .iter()
                        .zip(selection)
                        .filter(|(q, s)| **q != mesh.positions()[s.vertex as usize])
                        .count();
                    assert!(moved > size / 2, "{label}: {moved} of {size} moved");
                }
            }
        }
    }
    eprintln!("deform with the frame from the sums: GPU off the mirror by {worst:e} radii at most");
}

#[test]
fn dispatch_args_match_the_host_fold_and_the_cpu_mirror() {
    // The GPU-side sizes equal `dispatch_size` for the same count, folded or not, and an
    // overflowed count is clamped to the capacity.
    let mut gpu = gpu();
    for limit in [65_535, 7] {
        gpu.limits.max_compute_workgroups_per_dimension = limit;
        for &count in SIZES.iter().chain(&[100_003]) {
            for per_item in [1, 27] {
                let sizes = (count, per_item);
                let actual = run_dispatch_args(&gpu, count as u32, sizes, 64).expect("GPU run");
                let (x, y) = gpu.dispatch_size(count * per_item as usize, 64);
                assert_eq!(
                    actual,
                    [x, y, 1],
                    "count {count} × {per_item}, limit {limit}"
                );
                let params = slayer::gpu::DispatchParams {
                    workgroup_size: 64,
                    max_per_dimension: limit,
                    capacity: count as u32,
                    per_item,
                };
                let mut mirror = [0; 3];
                slayer::cpu::dispatch_args(&params, count as u32, &mut mirror);
                assert_eq!(
                    mirror, actual,
                    "mirror at count {count} × {per_item}, limit {limit}"
                );
            }
        }
    }
    // An overflowed count is clamped to the capacity before it is multiplied.
    let clamped = run_dispatch_args(&gpu, 1_000_000, (640, 1), 64).expect("GPU run");
    assert_eq!(clamped, [7, 2, 1]);
    let clamped = run_dispatch_args(&gpu, 1_000_000, (640, 3), 64).expect("GPU run");
    assert_eq!(clamped, [7, 5, 1]);
}

/// Pulled-back positions may differ by this share of the edge length: one flipped decision in
/// the last bisection rounds moves a result by 2⁻¹⁶ of its move, and the GPU may fuse the
/// closest-point arithmetic's multiply-adds.
const PROXIMITY_TOLERANCE: f32 = 1e-5;

fn longest_edge(mesh: &slayer::mesh::Mesh) -> f32 {
    (0..mesh.face_count())
        .filter(|&f| !mesh.is_face_dead(f))
        .map(|f| {
            let [a, b, c] = mesh.face_positions(f);
            a.distance(b).max(b.distance(c)).max(c.distance(a))
        })
        .fold(0.0, f32::max)
}

/// A step to test proximity on: the mesh at the step's start, its selection (a seeded shuffle
/// of the vertices that move) and every vertex's tentative position.
struct ProximityScene {
    name: &'static str,
    mesh: slayer::mesh::Mesh,
    order: Vec<u32>,
    targets: Vec<Vec3>,
    edge: f32,
}

/// A moving list over `listed`, each entry starting where `start` has its vertex, one slot in
/// seven vacant; about half the slots' vertices (vacant ones too) moved in `positions` by what
/// `step` draws. Returns the list and the vertices of its (not vacant) entries that moved.
fn half_moved_list(
    start: &[Vec3],
    positions: &mut [Vec3],
    listed: &[u32],
    (rng, step): (&mut ChaCha8Rng, impl Fn(&mut ChaCha8Rng) -> Vec3),
) -> (Vec<slayer::gpu::MovingVertex>, Vec<u32>) {
    let mut moving = Vec::with_capacity(listed.len());
    let mut moved = Vec::new();
    for (slot, &v) in listed.iter().enumerate() {
        let vertex = if slot % 7 == 6 { INVALID } else { v };
        moving.push(slayer::gpu::MovingVertex {
            start: start[v as usize].to_array(),
            vertex,
            ..Default::default()
        });
        if rng.random_bool(0.5) {
            positions[v as usize] += step(rng);
            if vertex != INVALID {
                moved.push(v);
            }
        }
    }
    (moving, moved)
}

fn shuffled(mut vertices: Vec<u32>, seed: u64) -> Vec<u32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for i in (1..vertices.len()).rev() {
        vertices.swap(i, rng.random_range(0..=i));
    }
    vertices
}

/// Each vertex of `moved` pushed down by `depth` (± 0.02) and jittered sideways by ± 0.02.
fn pushed_down(mesh: &slayer::mesh::Mesh, moved: &[u32], depth: f32, seed: u64) -> Vec<Vec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut targets = mesh.positions().to_vec();
    for &v in moved {
        targets[v as usize] += Vec3::new(
            rng.random_range(-0.02..0.02),
            rng.random_range(-0.02..0.02),
            -depth + rng.random_range(-0.02..0.02),
        );
    }
    targets
}

/// Two sheets 0.15 apart (edges 0.1), the upper one pushed 0.12 down: most of it comes within
/// the collision distance of the lower sheet and clamps.
fn pressed_sheets() -> ProximityScene {
    let mesh = slayer::scene::shapes::stacked_sheets(2, 80, 60, 0.1, 0.15);
    let upper: Vec<u32> = (0..mesh.vertex_count() as u32)
        .filter(|&v| mesh.vertex_layers()[v as usize] == 1)
        .collect();
    let targets = pushed_down(&mesh, &upper, 0.12, 71);
    ProximityScene {
        name: "pressed sheets",
        order: shuffled(upper, 72),
        mesh,
        targets,
        edge: 0.1,
    }
}

/// One sheet folded over itself (flat, a half-turn of radius 0.1, flat again 0.2 above), its
/// upper part pushed 0.17 down onto the lower: same-layer collisions outside the ring.
fn folded_sheet() -> ProximityScene {
    let mut mesh = slayer::scene::shapes::stacked_sheets(1, 80, 20, 0.1, 0.0);
    let (bend, radius) = (4.0f32, 0.1f32);
    let arc = std::f32::consts::PI * radius;
    let mut upper = Vec::new();
    for (v, p) in mesh.positions_mut().iter_mut().enumerate() {
        let s = p.x;
        if s <= bend {
            continue;
        }
        if s < bend + arc {
            let angle = (s - bend) / radius;
            p.x = bend + radius * angle.sin();
            p.z = radius - radius * angle.cos();
        } else {
            p.x = bend - (s - bend - arc);
            p.z = 2.0 * radius;
            upper.push(v as u32);
        }
    }
    let targets = pushed_down(&mesh, &upper, 0.17, 73);
    ProximityScene {
        name: "folded sheet",
        order: shuffled(upper, 74),
        mesh,
        targets,
        edge: 0.1,
    }
}

/// The proximity mirror's verdicts for `selection` of `scene`, with `current` positions.
fn cpu_proximity(
    scene: &ProximityScene,
    query: &slayer::gpu::ProximityQuery<'_>,
) -> Vec<slayer::gpu::PulledVertex> {
    let mesh = &scene.mesh;
    let starts: Vec<Vec3> = query
        .selection
        .iter()
        .map(|&v| mesh.positions()[v as usize])
        .collect();
    let (moving, rings) = slayer::gpu::moving_vertices(mesh, query.selection, &starts, query.ring);
    let topology = slayer::gpu::PackedTopology::of(mesh);
    let table_size = table_size_for(mesh.vertex_count());
    let params = slayer::gpu::proximity_params(query, topology.layout.vertex_rows_base, table_size);
    let flags: Vec<u32> = mesh.flags().iter().map(|f| f.bits()).collect();
    let table = slayer::cpu::hash_table(mesh.positions(), &flags, params.inv_cell_size, table_size);
    let flat: Vec<f32> = query.current.iter().flat_map(|p| p.to_array()).collect();
    let mut pulls = vec![0u32; query.selection.len()];
    slayer::cpu::proximity(
        &params,
        &slayer::cpu::ProximityInputs {
            positions: &flat,
            offsets: &table.offsets,
            entries: &table.entries,
            topology: &topology.words,
            moving: &moving,
            rings: &rings,
            marks: query.marks.unwrap_or(&[]),
            overlay_marks: &[],
            overlay_offsets: &[],
            overlay_entries: &[],
        },
        &mut pulls,
    );
    slayer::gpu::verdicts(&moving, &flat, &pulls)
}

/// `pipeline::step::pull_back` (the CPU backend's first pass) for the same step.
fn reference_pull_back(
    scene: &ProximityScene,
    selection: &[u32],
    distance: f32,
    ring: u32,
) -> Vec<Option<Vec3>> {
    let mesh = &scene.mesh;
    let grid = SpatialHash::build(mesh, scene.edge).unwrap();
    let mut current = mesh.clone();
    for &v in selection {
        current.positions_mut()[v as usize] = scene.targets[v as usize];
    }
    let active = vec![true; mesh.layer_count()];
    let state = slayer::pipeline::step::StrokeState {
        grid: Some(&grid),
        active: &active,
        parallel: false,
        collision_distance: distance,
        ring,
        max_edge: longest_edge(mesh).max(longest_edge(&current)),
    };
    let pairs: Vec<(u32, f32)> = selection.iter().map(|&v| (v, 1.0)).collect();
    let targets: Vec<Vec3> = selection
        .iter()
        .map(|&v| scene.targets[v as usize])
        .collect();
    let mut target_of = vec![INVALID; mesh.vertex_count()];
    for (i, &v) in selection.iter().enumerate() {
        target_of[v as usize] = i as u32;
    }
    let mut region = slayer::pipeline::step::Region::default();
    region.gather(&state, mesh, &pairs, &targets, &target_of);
    let mut scratch = slayer::pipeline::step::Scratch::default();
    selection
        .iter()
        .map(|&v| {
            let start = mesh.positions()[v as usize];
            if current.positions()[v as usize] == start {
                return None;
            }
            slayer::pipeline::step::pull_back(
                &state,
                &region,
                &current,
                v,
                start,
                None,
                &mut scratch,
            )
        })
        .collect()
}

/// Largest distance between two verdict lists over `edge`, after checking their flags agree.
fn compare_pulled(
    label: &str,
    actual: &[slayer::gpu::PulledVertex],
    expected: &[slayer::gpu::PulledVertex],
    edge: f32,
) -> f32 {
    assert_eq!(actual.len(), expected.len(), "{label}");
    let mut worst = 0.0f32;
    for (i, (a, e)) in actual.iter().zip(expected).enumerate() {
        assert_eq!(
            a.pulled, e.pulled,
            "{label}: entry {i} pulled {a:?} vs {e:?}"
        );
        let off = Vec3::from_array(a.position).distance(Vec3::from_array(e.position)) / edge;
        worst = worst.max(off);
    }
    assert!(
        worst <= PROXIMITY_TOLERANCE,
        "{label}: off by {worst:e} edge lengths"
    );
    worst
}

/// Both Jacobi passes of proximity on `scene` at awkward selection sizes (the largest folds its
/// dispatch into two dimensions): the mirror against `pull_back`, the GPU against the mirror;
/// then a second pass that tests only the faces of the vertices the first pulled back.
/// How a proximity check binds the packed topology.
#[derive(Clone, Copy, PartialEq)]
enum Binding {
    /// Whole, as the adapter's limits allow.
    Whole,
    /// Split over several bindings by a lowered binding limit.
    Paged,
}

fn check_proximity(scene: ProximityScene, binding: Binding) {
    let (distance, ring) = (0.05, 2);
    let (mut worst_mirror, mut worst_gpu) = (0.0f32, 0.0f32);
    let all = scene.order.len();
    let large_odd = if all >= 4001 { 4001 } else { all | 1 };
    let sizes = [0, 1, 63, 64, 65, 1000.min(all), large_odd.min(all)];
    let mut gpu = match binding {
        Binding::Whole => gpu(),
        Binding::Paged => {
            // Whole: positions, the hash table, the largest selection's entries. Paged: the
            // topology and the exclusion rings.
            let largest = &scene.order[..sizes[sizes.len() - 1]];
            let starts: Vec<Vec3> = largest
                .iter()
                .map(|&v| scene.mesh.positions()[v as usize])
                .collect();
            let (moving, rings) = slayer::gpu::moving_vertices(&scene.mesh, largest, &starts, ring);
            let vertices = scene.mesh.vertex_count() as u64;
            let unpaged = [
                12 * vertices,
                4 * (table_size_for(scene.mesh.vertex_count()) as u64 + 1),
                std::mem::size_of_val(moving.as_slice()) as u64,
            ];
            let topology = slayer::gpu::PackedTopology::of(&scene.mesh).words.len() as u64 * 4;
            let limit = binding_limit_paging(
                unpaged.into_iter().max().unwrap(),
                &[topology, 4 * rings.len() as u64],
            );
            gpu_with_binding_limit(limit)
        }
    };
    for (k, &size) in sizes.iter().enumerate() {
        let label = format!("{} at size {size}", scene.name);
        gpu.limits.max_compute_workgroups_per_dimension =
            if k + 1 == sizes.len() { 7 } else { 65_535 };
        let selection = &scene.order[..size];
        let mut current = scene.mesh.positions().to_vec();
        for &v in selection {
            current[v as usize] = scene.targets[v as usize];
        }
        let query = slayer::gpu::ProximityQuery {
            mesh: &scene.mesh,
            current: &current,
            selection,
            distance,
            ring,
            max_edge: longest_edge(&scene.mesh),
            cell_size: scene.edge,
            marks: None,
        };
        let mirror = cpu_proximity(&scene, &query);
        let reference: Vec<slayer::gpu::PulledVertex> =
            reference_pull_back(&scene, selection, distance, ring)
                .into_iter()
                .zip(selection)
                .map(|(p, &v)| match p {
                    Some(p) => slayer::gpu::PulledVertex {
                        position: p.to_array(),
                        pulled: 1,
                    },
                    None => slayer::gpu::PulledVertex {
                        position: current[v as usize].to_array(),
                        pulled: 0,
                    },
                })
                .collect();
        worst_mirror = worst_mirror.max(compare_pulled(
            &format!("{label}: mirror vs pull_back"),
            &mirror,
            &reference,
            scene.edge,
        ));
        let actual = slayer::gpu::run_proximity(&gpu, &query).expect("GPU run");
        worst_gpu = worst_gpu.max(compare_pulled(
            &format!("{label}: GPU vs mirror"),
            &actual,
            &mirror,
            scene.edge,
        ));
        if size >= 1000 {
            let clamped = mirror.iter().filter(|p| p.pulled == 1).count();
            assert!(clamped * 4 > size, "{label}: only {clamped} clamp");
        }

        // Second pass: the first's results written in, only faces it changed.
        let mut after = current.clone();
        let mut marks = vec![0u32; scene.mesh.vertex_count()];
        for (p, &v) in mirror.iter().zip(selection) {
            after[v as usize] = Vec3::from_array(p.position);
            marks[v as usize] = p.pulled;
        }
        let query = slayer::gpu::ProximityQuery {
            current: &after,
            marks: Some(&marks),
            ..query
        };
        let mirror = cpu_proximity(&scene, &query);
        let actual = slayer::gpu::run_proximity(&gpu, &query).expect("GPU run");
        worst_gpu = worst_gpu.max(compare_pulled(
            &format!("{label}, second pass: GPU vs mirror"),
            &actual,
            &mirror,
            scene.edge,
        ));
    }
    eprintln!(
        "proximity, {}{}: largest deviation mirror vs pull_back {worst_mirror:e}, GPU vs mirror {worst_gpu:e} (× edge)",
        scene.name,
        if binding == Binding::Paged {
            ", topology paged"
        } else {
            ""
        }
    );
}

#[test]
fn proximity_matches_cpu_mirror_and_the_cpu_pipeline_on_pressed_sheets() {
    check_proximity(pressed_sheets(), Binding::Whole);
}

#[test]
fn proximity_matches_cpu_mirror_and_the_cpu_pipeline_on_a_folded_sheet() {
    check_proximity(folded_sheet(), Binding::Whole);
}

#[test]
fn proximity_reads_a_topology_split_over_several_bindings() {
    check_proximity(pressed_sheets(), Binding::Paged);
}

/// Normals may differ by this much (unit vectors): the GPU may fuse the cross products'
/// multiply-adds.
const NORMAL_TOLERANCE: f32 = 1e-6;

/// The adapter for a normals kernel over `mesh`: with `Binding::Paged`, a binding limit that
/// keeps positions and normals (12 bytes a vertex) whole and splits the topology.
fn gpu_for_normals(binding: Binding, mesh: &Mesh) -> GpuContext {
    match binding {
        Binding::Whole => gpu(),
        Binding::Paged => {
            let unpaged = 12 * mesh.vertex_count() as u64;
            let topology = slayer::gpu::PackedTopology::of(mesh).words.len() as u64 * 4;
            gpu_with_binding_limit(binding_limit_paging(unpaged, &[topology]))
        }
    }
}

#[test]
fn vertex_normals_match_cpu_mirror_and_the_mesh() {
    check_vertex_normals(Binding::Whole);
}

#[test]
fn vertex_normals_read_a_topology_split_over_several_bindings() {
    check_vertex_normals(Binding::Paged);
}

fn check_vertex_normals(binding: Binding) {
    // Bumpy sheets (boundaries included) with their positions moved after the normals were
    // last computed; a seeded shuffle of the vertices at awkward sizes, the largest folded
    // into two dimensions. The mirror against `Mesh::recompute_normals_at`, the GPU against
    // the mirror; unlisted normals must stay as they were.
    let mut mesh = bumpy_sheets();
    let mut gpu = gpu_for_normals(binding, &mesh);
    let mut rng = ChaCha8Rng::seed_from_u64(600);
    for p in mesh.positions_mut() {
        p.z += rng.random_range(-0.01..0.01);
    }
    let order = shuffled((0..mesh.vertex_count() as u32).collect(), 601);
    let topology = slayer::gpu::PackedTopology::of(&mesh);
    let flat: Vec<f32> = mesh.positions().iter().flat_map(|p| p.to_array()).collect();
    let mut worst = 0.0f32;
    for (k, &size) in SIZES.iter().enumerate() {
        if k + 1 == SIZES.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let listed = &order[..size];
        let mut reference = mesh.clone();
        reference.recompute_normals_at(listed);
        let mut mirror: Vec<f32> = mesh.normals().iter().flat_map(|n| n.to_array()).collect();
        let params = slayer::gpu::NormalParams {
            count: size as u32,
            vertex_rows_base: topology.layout.vertex_rows_base,
            _pad0: 0,
            _pad1: 0,
        };
        slayer::cpu::vertex_normals(&params, &flat, &topology.words, listed, &mut mirror);
        let mirror: Vec<Vec3> = mirror.chunks(3).map(Vec3::from_slice).collect();
        assert_eq!(mirror, reference.normals(), "mirror at size {size}");
        let actual = slayer::gpu::run_vertex_normals(&gpu, &mesh, listed).expect("GPU run");
        let off = worst_relative(&actual, &mirror, 1.0);
        assert!(
            off <= NORMAL_TOLERANCE,
            "GPU off the mirror by {off:e} at size {size}"
        );
        worst = worst.max(off);
    }
    eprintln!("vertex_normals: largest deviation GPU vs mirror {worst:e}");
}

#[test]
fn moved_normals_match_cpu_mirror_and_the_mesh() {
    check_moved_normals(Binding::Whole);
}

#[test]
fn moved_normals_read_a_topology_split_over_several_bindings() {
    check_moved_normals(Binding::Paged);
}

fn check_moved_normals(binding: Binding) {
    // Moving lists over a seeded shuffle of the bumpy sheets' vertices at awkward sizes (the
    // largest folded into two dimensions): about half the entries moved off their start, one
    // slot in seven vacant. The mirror against `Mesh::recompute_normals_at` of every corner of
    // the faces around the moved vertices; the GPU against the mirror; every other normal must
    // stay as it was (stale, here).
    let start = bumpy_sheets();
    let mut gpu = gpu_for_normals(binding, &start);
    let order = shuffled((0..start.vertex_count() as u32).collect(), 602);
    let topology = slayer::gpu::PackedTopology::of(&start);
    let mut rng = ChaCha8Rng::seed_from_u64(603);
    let mut worst = 0.0f32;
    let mut refreshed_any = false;
    for (k, &size) in SIZES.iter().enumerate() {
        if k + 1 == SIZES.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let mut mesh = start.clone();
        // Vacant slots move too: their vertex's normals must stay all the same.
        let (moving, moved) = half_moved_list(
            start.positions(),
            mesh.positions_mut(),
            &order[..size],
            (&mut rng, |rng| {
                Vec3::new(0.0, 0.0, rng.random_range(-0.01..0.01))
            }),
        );
        let mut corners: Vec<u32> = moved
            .iter()
            .flat_map(|&v| mesh.faces_around(v).flat_map(|f| mesh.faces()[f as usize]))
            .collect();
        corners.sort_unstable();
        corners.dedup();
        refreshed_any |= !corners.is_empty();
        let mut reference = mesh.clone();
        reference.recompute_normals_at(&corners);
        let flat: Vec<f32> = mesh.positions().iter().flat_map(|p| p.to_array()).collect();
        let mut mirror: Vec<f32> = mesh.normals().iter().flat_map(|n| n.to_array()).collect();
        let params = slayer::gpu::NormalParams {
            count: size as u32,
            vertex_rows_base: topology.layout.vertex_rows_base,
            _pad0: 0,
            _pad1: 0,
        };
        slayer::cpu::moved_normals(&params, &flat, &topology.words, &moving, &mut mirror);
        let mirror: Vec<Vec3> = mirror.chunks(3).map(Vec3::from_slice).collect();
        assert_eq!(mirror, reference.normals(), "mirror at size {size}");
        let actual = slayer::gpu::run_moved_normals(&gpu, &mesh, &moving).expect("GPU run");
        let off = worst_relative(&actual, &mirror, 1.0);
        assert!(
            off <= NORMAL_TOLERANCE,
            "GPU off the mirror by {off:e} at size {size}"
        );
        for (v, (a, m)) in actual.iter().zip(&mirror).enumerate() {
            if corners.binary_search(&(v as u32)).is_err() {
                assert_eq!(a, m, "normal of vertex {v} changed at size {size}");
            }
        }
        worst = worst.max(off);
    }
    assert!(refreshed_any);
    eprintln!("moved_normals: largest deviation GPU vs mirror {worst:e}");
}

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
            let mut flat: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
            let mut mirror_marks = marks.clone();
            let mut next_count = 0;
            let mut finals = vec![0.0f32; 3 * count];
            let target_words: Vec<f32> = targets.iter().flat_map(|p| p.to_array()).collect();
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
            assert_eq!(actual.positions, expected, "{label}: positions");
            assert_eq!(actual.marks, mirror_marks, "{label}: marks");
            assert_eq!(actual.pulls, mirror_pulls, "{label}: amounts");
            assert_eq!(actual.next_count, next_count, "{label}: next count");
            if mode == ApplyMode::Gather {
                assert_eq!(
                    actual.finals,
                    bytemuck::cast_slice::<f32, Vec3>(&finals).to_vec(),
                    "{label}: finals"
                );
            }
            // What each mode means, on the mirror: untouched vertices stay, entries move, and
            // a pull lands where `verdicts` (and `pull_back`) put it.
            let any_pulled = pulls.iter().any(|&p| p != 0);
            let flat_before: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
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
/// sized by indirect dispatch, finals gathered) against `pipeline::step::clamp_moves`.
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
        let state = slayer::pipeline::step::StrokeState {
            grid: Some(&grid),
            active: &active,
            parallel: true,
            collision_distance: 0.5 * scene.edge,
            ring: 2,
            max_edge: longest_edge(mesh),
        };
        let mut target_of = vec![INVALID; mesh.vertex_count()];
        for (i, &(v, _)) in selection.iter().enumerate() {
            target_of[v as usize] = i as u32;
        }
        let mut region = slayer::pipeline::step::Region::default();
        region.gather(&state, mesh, &selection, &targets, &target_of);
        let mut on_cpu = mesh.clone();
        slayer::pipeline::step::clamp_moves(
            &state,
            &region,
            &mut on_cpu,
            &selection,
            &targets,
            &before,
        );
        let mut on_gpu = mesh.clone();
        let backstop = kernels.clamp(
            &state,
            &mut slayer::pipeline::step::Region::default(),
            &mut on_gpu,
            (&selection, &targets, &target_of),
            &before,
        );
        assert_eq!(kernels.failure(), None);
        // The GPU filtered the backstop's pairs too: no region needed.
        assert!(
            matches!(backstop, slayer::pipeline::step::Backstop::Undecided(_)),
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
            worst <= PROXIMITY_TOLERANCE,
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
                max_edge: longest_edge(&scene.mesh),
                cell_size: scene.edge,
                capacity: 1 << 16,
            };
            let actual = slayer::gpu::run_backstop(&gpu, &query).expect("GPU run");

            let mesh = &scene.mesh;
            let (moving, moved) = slayer::gpu::backstop_inputs(&query);
            let topology = slayer::gpu::PackedTopology::of(mesh);
            let table_size = table_size_for(mesh.vertex_count());
            let params = slayer::gpu::backstop_query_params(
                &query,
                topology.layout.vertex_rows_base,
                table_size,
            );
            let flags: Vec<u32> = mesh.flags().iter().map(|f| f.bits()).collect();
            let table =
                slayer::cpu::hash_table(mesh.positions(), &flags, params.inv_cell_size, table_size);
            let flat: Vec<f32> = current.iter().flat_map(|p| p.to_array()).collect();
            let mut mirror = slayer::cpu::backstop(
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

/// The mirror of `moving_entries` over `selected` with `capacity` slots.
fn cpu_moving_entries(
    mesh: &slayer::mesh::Mesh,
    selected: &[SelectedVertex],
    (capacity, ring, ring_stride): (usize, u32, u32),
) -> slayer::gpu::BuiltEntries {
    let topology = slayer::gpu::PackedTopology::of(mesh);
    let params = slayer::gpu::EntryParams {
        ring_stride,
        ..slayer::gpu::entry_params(capacity, ring, topology.layout.vertex_rows_base)
    };
    let mut built = slayer::gpu::BuiltEntries {
        moving: vec![slayer::gpu::MovingVertex::default(); capacity],
        rings: vec![0; capacity * ring_stride as usize],
        overflows: 0,
    };
    slayer::cpu::moving_entries(
        &params,
        &slayer::cpu::EntryInputs {
            positions: bytemuck::cast_slice(mesh.positions()),
            layers: mesh.vertex_layers(),
            selected,
            selection_count: selected.len() as u32,
            topology: &topology.words,
        },
        &mut slayer::cpu::EntryOutputs {
            moving: &mut built.moving,
            rings: &mut built.rings,
            overflows: &mut built.overflows,
        },
    );
    built
}

#[test]
fn moving_entries_match_the_cpu_mirror_and_the_hosts_rings() {
    check_moving_entries(Binding::Whole);
}

#[test]
fn moving_entries_read_a_topology_split_over_several_bindings() {
    check_moving_entries(Binding::Paged);
}

/// `moving_entries` on the GPU equals its mirror word for word, and each entry equals the one
/// the host builds (`moving_vertices`: same start, vertex and layer, the same ring as a set),
/// for the unsorted list of a selection at awkward sizes, with vacant slots past it and with
/// fewer slots than it has; rings of one to four, and rings cut short by too little room.
fn check_moving_entries(binding: Binding) {
    let mesh = bumpy_sheets();
    let all: Vec<u32> = shuffled((0..mesh.vertex_count() as u32).collect(), 91);
    let list: Vec<SelectedVertex> = all
        .iter()
        .map(|&vertex| SelectedVertex {
            vertex,
            weight: 0.5,
        })
        .collect();
    let stride = slayer::gpu::RING_STRIDE;
    let (gpu, sizes) = match binding {
        Binding::Whole => (gpu(), SIZES.to_vec()),
        Binding::Paged => {
            let sizes = vec![0, 1, 65, 1000];
            let topology = slayer::gpu::PackedTopology::of(&mesh).words.len() as u64 * 4;
            let unpaged = (12 * mesh.vertex_count() as u64).max(slayer::gpu::ring_bytes(1037));
            let limit = binding_limit_paging(unpaged, &[topology]);
            (gpu_with_binding_limit(limit), sizes)
        }
    };
    let mut overflowed = 0;
    for &size in &sizes {
        for ring in 1..=4 {
            let selected = &list[..size];
            // Vacant slots past the list; for the largest, fewer slots than entries.
            for capacity in [size + 37, size / 2] {
                for room in [stride, 16] {
                    let label = format!("size {size}, ring {ring}, {capacity} slots of {room}");
                    let how = (capacity, ring, room);
                    let actual = slayer::gpu::run_moving_entries(&gpu, &mesh, selected, how)
                        .expect("GPU run");
                    let mirror = cpu_moving_entries(&mesh, selected, how);
                    assert_eq!(actual, mirror, "{label}: GPU against the mirror");
                    overflowed += (actual.overflows > 0) as usize;
                    if room < stride {
                        continue;
                    }
                    assert_eq!(actual.overflows, 0, "{label}: a ring of {ring} fits");
                    let built = selected.len().min(capacity);
                    let vertices: Vec<u32> = selected[..built].iter().map(|s| s.vertex).collect();
                    let starts: Vec<Vec3> = vertices
                        .iter()
                        .map(|&v| mesh.positions()[v as usize])
                        .collect();
                    let (host, host_rings) =
                        slayer::gpu::moving_vertices(&mesh, &vertices, &starts, ring);
                    for (i, entry) in actual.moving.iter().enumerate() {
                        if i >= built {
                            assert_eq!(entry.vertex, INVALID, "{label}: slot {i} is vacant");
                            assert_eq!(entry.ring_start, entry.ring_end, "{label}: slot {i}");
                            continue;
                        }
                        let expected = &host[i];
                        assert_eq!(
                            (entry.start, entry.vertex, entry.layer),
                            (expected.start, expected.vertex, expected.layer),
                            "{label}: entry {i}"
                        );
                        let mut ring_words = actual.rings
                            [entry.ring_start as usize..entry.ring_end as usize]
                            .to_vec();
                        assert_eq!(ring_words[0], entry.vertex, "{label}: the vertex first");
                        let mut host_ring = host_rings
                            [expected.ring_start as usize..expected.ring_end as usize]
                            .to_vec();
                        ring_words.sort_unstable();
                        host_ring.sort_unstable();
                        assert_eq!(ring_words, host_ring, "{label}: ring of entry {i}");
                    }
                }
            }
        }
    }
    assert!(overflowed > 0, "sixteen words are too few for some ring");
}

/// Overlay slots over `vertex_count` vertices at `filed` (packed): `held` members in slots in
/// the order given, marks slot + 1, room for `room`.
fn overlay_slots(filed: &[Vec3], held: &[u32], room: usize) -> slayer::cpu::OverlaySlots {
    let mut slots = slayer::cpu::OverlaySlots {
        marks: vec![0; filed.len()],
        members: vec![INVALID; room],
        member_count: held.len() as u32,
        filed_at: filed.iter().flat_map(|p| p.to_array()).collect(),
    };
    for (slot, &v) in held.iter().enumerate() {
        slots.members[slot] = v;
        slots.marks[v as usize] = slot as u32 + 1;
    }
    slots
}

/// The members of `slots` (sorted), checked against the marks: slot `s` holds `v` exactly
/// when `marks[v]` is `s + 1`, and no other vertex is marked.
fn checked_members(slots: &slayer::cpu::OverlaySlots, room: usize, what: &str) -> Vec<u32> {
    let taken = (slots.member_count as usize).min(room);
    let mut members = slots.members[..taken].to_vec();
    for (s, &v) in members.iter().enumerate() {
        assert_eq!(slots.marks[v as usize], s as u32 + 1, "{what}: mark of {v}");
    }
    let marked = slots.marks.iter().filter(|&&m| m != 0).count();
    assert_eq!(marked, taken, "{what}: marked vertices");
    members.sort_unstable();
    members
}

#[test]
fn overlay_members_file_the_moved_entries_as_the_cpu_mirror_does() {
    // Moving lists over a seeded shuffle of 9000 vertices at awkward sizes (the largest folded
    // into two dimensions), one slot in seven vacant, about half the entries moved; the overlay
    // already holds every eleventh vertex, so some moved entries are members and keep their
    // slot. Slots are handed out in atomic order on the GPU: members compare as sets, marks
    // must name each member's slot, filed positions bit for bit.
    let mut gpu = gpu();
    let vertex_count = 9000;
    let start = random_positions(vertex_count, 910, 3.0);
    let held: Vec<u32> = (0..vertex_count as u32).step_by(11).collect();
    let order = shuffled((0..vertex_count as u32).collect(), 911);
    let mut rng = ChaCha8Rng::seed_from_u64(912);
    for (k, &size) in SIZES.iter().enumerate() {
        if k + 1 == SIZES.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let mut positions = start.clone();
        let (moving, moved) = half_moved_list(
            &start,
            &mut positions,
            &order[..size],
            (&mut rng, |rng| {
                Vec3::new(0.0, 0.0, rng.random_range(0.001..0.3))
            }),
        );
        let room = held.len() + size;
        let before = overlay_slots(&start, &held, room);
        let flat: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
        let params = slayer::gpu::OverlayParams {
            count: size as u32,
            room: room as u32,
            table_mask: 0,
            inv_cell_size: 1.0,
        };
        let mut mirror = before.clone();
        slayer::cpu::overlay_members(&params, &flat, &moving, &mut mirror);
        let actual =
            slayer::gpu::run_overlay_members(&gpu, &positions, &moving, &before).expect("GPU run");
        // What the mirror must do: the held members and every moved entry, filed where it is.
        let mut expected: Vec<u32> = held.iter().chain(&moved).copied().collect();
        expected.sort_unstable();
        expected.dedup();
        let mirror_members = checked_members(&mirror, room, "mirror");
        assert_eq!(mirror_members, expected, "mirror members at size {size}");
        let mut filed = start.clone();
        for &v in &moved {
            filed[v as usize] = positions[v as usize];
        }
        let filed: Vec<f32> = filed.iter().flat_map(|p| p.to_array()).collect();
        assert_eq!(
            mirror.filed_at, filed,
            "mirror filed positions at size {size}"
        );
        // The GPU as the mirror, held slots untouched.
        assert_eq!(
            actual.member_count, mirror.member_count,
            "count at size {size}"
        );
        assert_eq!(
            checked_members(&actual, room, "GPU"),
            mirror_members,
            "size {size}"
        );
        assert_eq!(
            &actual.members[..held.len()],
            &held[..],
            "held slots at size {size}"
        );
        assert_eq!(
            actual.filed_at, mirror.filed_at,
            "filed positions at size {size}"
        );
    }
    // A room too small: the count still says how many slots were wanted, the vertices past the
    // room stay unmarked and unfiled, and those within it are consistent.
    let size = 1000;
    let moving: Vec<slayer::gpu::MovingVertex> = order[..size]
        .iter()
        .map(|&v| slayer::gpu::MovingVertex {
            start: (start[v as usize] - Vec3::X).to_array(),
            vertex: v,
            ..Default::default()
        })
        .collect();
    let room = held.len() + 10;
    let before = overlay_slots(&start, &held, room);
    let actual = slayer::gpu::run_overlay_members(&gpu, &start, &moving, &before).expect("GPU run");
    let newly = order[..size]
        .iter()
        .filter(|&&v| before.marks[v as usize] == 0)
        .count();
    assert_eq!(actual.member_count as usize, held.len() + newly);
    assert_eq!(
        checked_members(&actual, room, "GPU, room short").len(),
        room
    );
}

#[test]
fn overlay_tables_rebuilt_from_slots_match_the_cpu_chain_and_the_host_filing() {
    // Members in a shuffled slot order at awkward counts, in rooms with spare slots (dead to
    // the counting sort), filed at positions apart from the vertices' own: `overlay_keys`, the
    // counting sort and `overlay_entries` on the GPU against their mirrors chained
    // (`cpu::overlay_slot_table`), bucket sets identical; the mirror against the host's filing
    // (`gpu::overlay_table`) of the same members at the same positions.
    let mut gpu = gpu();
    let vertex_count = 12000;
    let cell_size = 0.25f32;
    let inv = 1.0 / cell_size;
    let filed = random_positions(vertex_count, 920, 2.0);
    let order = shuffled((0..vertex_count as u32).collect(), 921);
    for (k, &size) in SIZES.iter().enumerate() {
        if k + 1 == SIZES.len() {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        let room = size + size / 3 + 1;
        let slots = overlay_slots(&filed, &order[..size], room);
        let table_size = table_size_for(room);
        let params = slayer::gpu::OverlayParams {
            count: room as u32,
            room: room as u32,
            table_mask: table_size - 1,
            inv_cell_size: inv,
        };
        let mirror = slayer::cpu::overlay_slot_table(&params, &slots).canonical();
        let mut members = order[..size].to_vec();
        members.sort_unstable();
        let host = slayer::gpu::overlay_table_sized(&filed, &members, inv, table_size).canonical();
        assert_eq!(mirror, host, "mirror vs host filing at size {size}");
        let actual = slayer::gpu::run_overlay_table(&gpu, &slots, table_size, inv)
            .expect("GPU run")
            .canonical();
        assert_eq!(actual, mirror, "GPU vs mirror at size {size}");
    }
}

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
    let flat: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
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
        let flat_targets: Vec<f32> = targets.iter().flat_map(|p| p.to_array()).collect();
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
    let flat_targets: Vec<f32> = targets.iter().flat_map(|p| p.to_array()).collect();
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

#[test]
fn sample_gate_stages_match_the_cpu_mirror() {
    use slayer::gpu::{GateParams, GateStage, GateStatus, MovingVertex};
    let mut gpu = gpu();
    let run = |gpu: &GpuContext,
               params: &GateParams,
               overflows: u32,
               (count, moving, status): (u32, &[MovingVertex], GateStatus)| {
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
    };
    // Opening: the longest move reset; the selection emptied only in a stopped run.
    for stopped in [0, GateStatus::MOVE, GateStatus::EARLIER] {
        let status = GateStatus {
            stopped,
            longest: 7.5f32.to_bits(),
            edge: 2.0f32.to_bits(),
            _pad: 0,
        };
        let open = GateParams::new(0, GateStage::Open, (0.0, 0.0));
        let (count, _, after) = run(&gpu, &open, 0, (77, &[], status));
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
                        _pad: 0,
                    };
                    let decide = GateParams::new(capacity, GateStage::Decide, (assumed, max_edge));
                    let (after_count, _, after) =
                        run(&gpu, &decide, overflows, (count, &[], status));
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
            let (_, after, _) = run(&gpu, &vacate, 0, (size as u32, &moving, status));
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
    let initial = longest_edge(&start);
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
        let params = slayer::gpu::NormalParams {
            count: size as u32,
            vertex_rows_base: topology.layout.vertex_rows_base,
            _pad0: 0,
            _pad1: 0,
        };
        let flat: Vec<f32> = mesh.positions().iter().flat_map(|p| p.to_array()).collect();
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
