//! Which cells of the grid hold a vertex, kept beside the bucket table so that a box query
//! probes only those: a surface fills a few percent of its box's cells (a brush's box over a
//! bumpy sheet at 1M faces: about 50K cells, 5K of them holding a vertex), and probing an empty
//! cell costs a hash and a read of a bucket table far larger than the cache.
//!
//! Cells are grouped in blocks of 4 × 4 × 4, each occupied block holding a 64-bit mask of its
//! occupied cells. The mask is exact: a cell's bit is set while a vertex is filed there.

use glam::IVec3;
use rayon::prelude::*;
use rustc_hash::FxHashMap;

/// log₂ of a block's side in cells.
const BLOCK_SHIFT: i32 = 2;
const BLOCK_SIDE: i32 = 1 << BLOCK_SHIFT;

/// The occupied cells, as one mask per occupied block.
#[derive(Debug, Clone, Default)]
pub(super) struct Occupancy {
    blocks: FxHashMap<IVec3, u64>,
}

/// The block of `cell` and the bit of `cell` in its mask. The shift floors negative
/// coordinates too, so every cell has one block.
#[inline]
fn block_and_bit(cell: IVec3) -> (IVec3, u64) {
    let block = cell >> BLOCK_SHIFT;
    let local = cell & (BLOCK_SIDE - 1);
    let index = local.x + BLOCK_SIDE * (local.y + BLOCK_SIDE * local.z);
    (block, 1u64 << index)
}

impl Occupancy {
    /// The occupancy of the `cells` that `filed` accepts (a grid's set-up, at millions of
    /// vertices): a chunk at a time, its bits sorted by block in parallel and each block's
    /// mask filed once, instead of a table update per vertex; the chunks bound what the sort
    /// holds to a few megabytes whatever the mesh.
    pub(super) fn of_cells(cells: &[IVec3], filed: impl Fn(IVec3) -> bool + Sync) -> Occupancy {
        Occupancy::of_cells_in_chunks(cells, filed, 1 << 20)
    }

    fn of_cells_in_chunks(
        cells: &[IVec3],
        filed: impl Fn(IVec3) -> bool + Sync,
        chunk_len: usize,
    ) -> Occupancy {
        let mut blocks = FxHashMap::default();
        let mut bits: Vec<([i32; 3], u64)> = Vec::new();
        for chunk in cells.chunks(chunk_len) {
            bits.clear();
            bits.par_extend(chunk.par_iter().filter(|&&c| filed(c)).map(|&cell| {
                let (block, bit) = block_and_bit(cell);
                (block.to_array(), bit)
            }));
            bits.par_sort_unstable_by_key(|&(block, _)| block);
            for run in bits.chunk_by(|a, b| a.0 == b.0) {
                let mask = run.iter().fold(0, |mask, &(_, bit)| mask | bit);
                *blocks.entry(IVec3::from_array(run[0].0)).or_insert(0) |= mask;
            }
        }
        Occupancy { blocks }
    }

    /// Marks `cell` as holding a vertex.
    pub(super) fn set(&mut self, cell: IVec3) {
        let (block, bit) = block_and_bit(cell);
        *self.blocks.entry(block).or_insert(0) |= bit;
    }

    /// Marks `cell` as holding none (its last vertex left).
    pub(super) fn clear(&mut self, cell: IVec3) {
        let (block, bit) = block_and_bit(cell);
        if let Some(mask) = self.blocks.get_mut(&block) {
            *mask &= !bit;
            if *mask == 0 {
                self.blocks.remove(&block);
            }
        }
    }

    /// Whether `cell` is marked as holding a vertex.
    pub(super) fn is_set(&self, cell: IVec3) -> bool {
        let (block, bit) = block_and_bit(cell);
        self.blocks.get(&block).is_some_and(|mask| mask & bit != 0)
    }

    /// Cells marked, counted (for the consistency check).
    pub(super) fn count(&self) -> usize {
        self.blocks.values().map(|m| m.count_ones() as usize).sum()
    }

    /// Heap bytes held, approximately (key, mask and a control byte per slot).
    pub(super) fn memory_bytes(&self) -> usize {
        self.blocks.capacity() * (std::mem::size_of::<(IVec3, u64)>() + 1)
    }

    /// The occupied cells of the box of cells `[a, b]`, each given to `f`, in the order
    /// z, then y, then x ascending (the order a walk over every cell of the box meets them).
    pub(super) fn for_each_occupied(&self, a: IVec3, b: IVec3, mut f: impl FnMut(IVec3)) {
        let (first, last) = (a >> BLOCK_SHIFT, b >> BLOCK_SHIFT);
        let span = (last - first + IVec3::ONE).as_uvec3();
        let blocks = (span.x * span.y * span.z) as usize;
        // The box's blocks' masks, read once each (zero for an empty block); a small box's
        // on the stack (the remesher's checks ask thousands of them).
        let mut on_stack = [0u64; 32];
        let mut on_heap = Vec::new();
        let masks: &mut [u64] = if blocks <= on_stack.len() {
            &mut on_stack[..blocks]
        } else {
            on_heap.resize(blocks, 0);
            &mut on_heap
        };
        let mut slots = masks.iter_mut();
        for bz in first.z..=last.z {
            for by in first.y..=last.y {
                for bx in first.x..=last.x {
                    let mask = self.blocks.get(&IVec3::new(bx, by, bz)).copied();
                    *slots.next().expect("a slot per block") = mask.unwrap_or(0);
                }
            }
        }
        for z in a.z..=b.z {
            let (bz, lz) = ((z >> BLOCK_SHIFT) - first.z, z & (BLOCK_SIDE - 1));
            for y in a.y..=b.y {
                let (by, ly) = ((y >> BLOCK_SHIFT) - first.y, y & (BLOCK_SIDE - 1));
                let row = ((bz as u32 * span.y + by as u32) * span.x) as usize;
                let shift = BLOCK_SIDE * (ly + BLOCK_SIDE * lz);
                let mut x = a.x;
                loop {
                    // This block's cells on the row, as the low bits; `x | 3` is the block's
                    // last cell, negative coordinates included.
                    let bx = (x >> BLOCK_SHIFT) - first.x;
                    let cells = (masks[row + bx as usize] >> shift) & ((1 << BLOCK_SIDE) - 1);
                    let end = (x | (BLOCK_SIDE - 1)).min(b.x);
                    if cells != 0 {
                        for cx in x..=end {
                            if cells & (1 << (cx & (BLOCK_SIDE - 1))) != 0 {
                                f(IVec3::new(cx, y, z));
                            }
                        }
                    }
                    if end == b.x {
                        break;
                    }
                    x = end + 1;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cells in and around a few blocks, negative coordinates and repeats included.
    fn cells() -> Vec<IVec3> {
        (0..500)
            .map(|i: i32| IVec3::new(i % 11 - 5, (i * 7) % 13 - 6, (i * 3) % 9 - 4))
            .collect()
    }

    #[test]
    fn built_in_chunks_or_at_once_or_cell_by_cell_the_masks_agree() {
        let cells = cells();
        let keep = |c: IVec3| c.x != 0;
        let whole = Occupancy::of_cells_in_chunks(&cells, keep, cells.len());
        let chunked = Occupancy::of_cells_in_chunks(&cells, keep, 7);
        let mut one_by_one = Occupancy::default();
        for &c in cells.iter().filter(|&&c| keep(c)) {
            one_by_one.set(c);
        }
        assert_eq!(whole.blocks, chunked.blocks);
        assert_eq!(whole.blocks, one_by_one.blocks);
        assert!(cells.iter().all(|&c| whole.is_set(c) == keep(c)));
    }

    #[test]
    fn a_box_meets_its_occupied_cells_in_walk_order_and_cleared_cells_not_at_all() {
        let cells = cells();
        let mut occupancy = Occupancy::of_cells(&cells, |_| true);
        // (-4, 1, -1): inside the box.
        occupancy.clear(cells[1]);
        let (a, b) = (IVec3::new(-6, -5, -3), IVec3::new(3, 4, 2));
        let mut walked = Vec::new();
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    let cell = IVec3::new(x, y, z);
                    if occupancy.is_set(cell) {
                        walked.push(cell);
                    }
                }
            }
        }
        let mut met = Vec::new();
        occupancy.for_each_occupied(a, b, |cell| met.push(cell));
        assert!(!met.contains(&cells[1]));
        assert!(!walked.is_empty());
        assert_eq!(met, walked);
    }
}
