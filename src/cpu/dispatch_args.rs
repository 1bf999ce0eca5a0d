//! Mirror of `wgsl/dispatch_args.wgsl`.

use crate::abi::DispatchParams;

/// `[x, y, z]` workgroup counts covering `min(count, capacity) · per_item` invocations.
pub fn dispatch_args(params: &DispatchParams, count: u32, args: &mut [u32; 3]) {
    let invocations = count.min(params.capacity) * params.per_item;
    let groups = invocations.div_ceil(params.workgroup_size);
    let max_x = params.max_per_dimension.max(1);
    *args = if groups <= max_x {
        [groups, 1, 1]
    } else {
        [max_x, groups.div_ceil(max_x), 1]
    };
}
