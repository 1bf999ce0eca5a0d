// Indirect dispatch sizes from a count the GPU produced (the selection count), so the passes
// after `select` run over the selection without a read-back; `per_item` invocations per item
// (a proximity pass runs one per cell of each entry's box). Folds into y exactly as
// `GpuContext::dispatch_size` does on the host; kernels flatten with `flat_index`.
// CPU mirror: src/cpu/dispatch_args.rs.

struct DispatchParams {
    // Workgroup size of the kernel the arguments are for.
    workgroup_size: u32,
    // The adapter's max_compute_workgroups_per_dimension.
    max_per_dimension: u32,
    // Clamp on the count (the buffer's capacity: an overflowed count must not over-dispatch).
    capacity: u32,
    // Invocations per item (the host checks that capacity · per_item fits a u32).
    per_item: u32,
}

@group(0) @binding(0) var<uniform> params: DispatchParams;
@group(0) @binding(1) var<storage, read> count: u32;
// x, y, z workgroup counts, as `dispatch_workgroups_indirect` reads them.
@group(0) @binding(2) var<storage, read_write> args: array<u32, 3>;

@compute @workgroup_size(1)
fn main() {
    let invocations = min(count, params.capacity) * params.per_item;
    let groups = (invocations + params.workgroup_size - 1u) / params.workgroup_size;
    let max_x = max(params.max_per_dimension, 1u);
    if groups <= max_x {
        args = array<u32, 3>(groups, 1u, 1u);
    } else {
        args = array<u32, 3>(max_x, (groups + max_x - 1u) / max_x, 1u);
    }
}
