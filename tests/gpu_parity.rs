//! Every WGSL kernel against its CPU mirror, on the adapter the machine has (lavapipe in CI).
//! These tests never skip: a machine without any Vulkan adapter fails them, and
//! `tools/test.sh` installs lavapipe so that CI always has one.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slayer::gpu::{AdapterChoice, CellKeyParams, GpuContext, run_cell_keys};

fn gpu() -> GpuContext {
    let gpu = GpuContext::new(AdapterChoice {
        allow_software: true,
    })
    .unwrap_or_else(|e| panic!("GPU tests need an adapter (run tools/test.sh): {e}"));
    eprintln!("GPU tests on: {}", gpu.adapter);
    gpu
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
