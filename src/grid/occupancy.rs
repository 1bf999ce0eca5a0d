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
    /// The occupancy of `cells` (every one holding a vertex): their bits sorted by block in
    /// parallel, then each block's mask filed once, instead of a table update per vertex
    /// (a grid's set-up at millions of vertices).
    pub(super) fn of_cells(cells: &[IVec3]) -> Occupancy {
        let mut bits: Vec<([i32; 3], u64)> = cells
            .par_iter()
            .map(|&cell| {
                let (block, bit) = block_and_bit(cell);
                (block.to_array(), bit)
            })
            .collect();
        bits.par_sort_unstable_by_key(|&(block, _)| block);
        let runs = bits.chunk_by(|a, b| a.0 == b.0);
        let mut blocks =
            FxHashMap::with_capacity_and_hasher(runs.clone().count(), Default::default());
        for run in runs {
            let mask = run.iter().fold(0, |mask, &(_, bit)| mask | bit);
            blocks.insert(IVec3::from_array(run[0].0), mask);
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
        for (k, mask) in masks.iter_mut().enumerate() {
            let k = k as u32;
            let at = IVec3::new(
                (k % span.x) as i32,
                ((k / span.x) % span.y) as i32,
                (k / (span.x * span.y)) as i32,
            );
            *mask = self.blocks.get(&(first + at)).copied().unwrap_or(0);
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
