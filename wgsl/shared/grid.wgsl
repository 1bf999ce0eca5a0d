// The uniform grid's cell arithmetic, shared by every kernel that touches the spatial hash.
// Mirrors `src/grid/mod.rs::cell_coordinates` and `src/grid/hash.rs::hash_cell` bit for bit.

// Row and slab strides (Teschner et al. 2003's primes). x is unscaled so a row of cells fills
// consecutive buckets (see src/grid/hash.rs).
const HASH_PRIME_Y: u32 = 19349663u;
const HASH_PRIME_Z: u32 = 83492791u;

// The cell containing `p`. A multiply (correctly rounded on every backend) rather than a divide.
fn cell_of(p: vec3<f32>, inv_cell_size: f32) -> vec3<i32> {
    return vec3<i32>(floor(p * inv_cell_size));
}

// Slot of `cell` in a power-of-two table; `mask` is the table size minus one.
fn hash_cell(cell: vec3<i32>, mask: u32) -> u32 {
    let u = bitcast<vec3<u32>>(cell);
    return (u.x + u.y * HASH_PRIME_Y + u.z * HASH_PRIME_Z) & mask;
}

// Flattened invocation index for dispatches wider than 65535 workgroups in x.
fn flat_index(global_id: vec3<u32>, workgroups: vec3<u32>, workgroup_size: u32) -> u32 {
    return global_id.x + global_id.y * workgroups.x * workgroup_size;
}
