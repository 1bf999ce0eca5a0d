//! Hashing cell coordinates into a fixed-size table: the scheme of Teschner et al. 2003, shared
//! bit for bit with `wgsl/shared/hash.wgsl` so CPU and GPU tables agree.

use glam::IVec3;

/// Index of a cell in a power-of-two hash table.
pub type CellKey = u32;

/// Teschner's primes; wrapping arithmetic on the two's-complement bits, as WGSL does.
const PRIMES: [u32; 3] = [73_856_093, 19_349_663, 83_492_791];

/// Table slot of `cell` in a table of `table_size` slots (a power of two).
#[inline]
pub fn hash_cell(cell: IVec3, table_size: u32) -> CellKey {
    debug_assert!(table_size.is_power_of_two());
    let h = (cell.x as u32).wrapping_mul(PRIMES[0])
        ^ (cell.y as u32).wrapping_mul(PRIMES[1])
        ^ (cell.z as u32).wrapping_mul(PRIMES[2]);
    h & (table_size - 1)
}
