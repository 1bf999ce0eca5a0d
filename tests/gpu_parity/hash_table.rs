//! The hash-table build (`cell_keys`, `cell_counts`, `scan`, `scan_add`, `scatter`) against
//! its mirrors, chained, and against the CPU grid.

use glam::Vec3;
use slayer::gpu::{
    CellKeyParams, CountParams, CsrTable, run_cell_counts, run_cell_keys, run_exclusive_scan,
    run_hash_table, run_scatter, table_size_for,
};
use slayer::grid::{SpatialHash, cell_coordinates, hash_cell};
use slayer::mesh::{INVALID, VertexFlags};

use crate::common::{SIZES, flag_bits, gpu, packed, random_flags, random_positions, random_u32s};

fn cpu_cell_keys(positions: &[Vec3], inv_cell_size: f32, table_size: u32) -> Vec<u32> {
    let params = CellKeyParams {
        count: positions.len() as u32,
        table_mask: table_size - 1,
        inv_cell_size,
        _pad: 0,
    };
    let flat = packed(positions);
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
    let flags = flag_bits(&mesh);
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
