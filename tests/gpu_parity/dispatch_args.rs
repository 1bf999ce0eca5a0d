//! `dispatch_args` against the host's fold and its mirror.

use slayer::gpu::run_dispatch_args;

use crate::common::{SIZES, gpu};

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
