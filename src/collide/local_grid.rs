//! A dense grid of face boxes over one brush step's region: the collision broad phase.
//!
//! The global spatial hash files vertices; a proximity query through it must probe every cell
//! within `d + longest edge` of the point (over a hundred hash probes). Per step we instead
//! gather the region's faces once through the hash and file their boxes in a small dense array
//! (counting sort, no hashing), so a query reads only the few cells its own box covers.

use glam::{IVec3, Vec3};

use crate::geom::Aabb;

/// Cells per axis at most for a grid of few faces; larger regions get larger cells…
const MAX_CELLS_PER_AXIS: f32 = 64.0;
/// …unless the grid files many faces: then up to this many cells a face. A whole-mesh remesh
/// files every face; held to 64 cells an axis, a 1M-face torus had cells 7 edges wide and
/// every query read hundreds of faces.
const MAX_CELLS_PER_FACE: usize = 8;

#[derive(Debug, Clone, Default)]
pub struct LocalFaceGrid {
    origin: Vec3,
    inv_cell: f32,
    dims: IVec3,
    /// `offsets[c]..offsets[c + 1]` indexes `entries` for cell `c`.
    offsets: Vec<u32>,
    /// Local face indices (positions in the face list the grid was built from).
    entries: Vec<u32>,
    cursor: Vec<u32>,
}

impl LocalFaceGrid {
    /// Files `boxes[i]` (local face `i`) in every cell it overlaps. `region` bounds all boxes;
    /// `cell` is the preferred cell side.
    pub fn build(&mut self, boxes: &[Aabb], region: Aabb, cell: f32) {
        let extent = (region.max - region.min).max(Vec3::splat(cell));
        let axis_cap = MAX_CELLS_PER_AXIS.powi(3) as usize;
        let mut cell = cell;
        if boxes.len() * MAX_CELLS_PER_FACE <= axis_cap {
            cell = cell.max(extent.max_element() / MAX_CELLS_PER_AXIS);
        } else {
            let cells = |cell: f32| {
                let dims = (extent / cell).floor() + Vec3::ONE;
                dims.x as f64 * dims.y as f64 * dims.z as f64
            };
            while cells(cell) > (boxes.len() * MAX_CELLS_PER_FACE) as f64 {
                cell *= 1.25;
            }
        }
        self.origin = region.min;
        self.inv_cell = 1.0 / cell;
        self.dims = ((extent * self.inv_cell).floor().as_ivec3() + IVec3::ONE).max(IVec3::ONE);
        let cell_count = (self.dims.x * self.dims.y * self.dims.z) as usize;
        self.offsets.clear();
        self.offsets.resize(cell_count + 1, 0);
        for b in boxes {
            let (lo, hi) = self.cell_span(b);
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let c = self.index(IVec3::new(x, y, z));
                        self.offsets[c + 1] += 1;
                    }
                }
            }
        }
        for c in 0..cell_count {
            self.offsets[c + 1] += self.offsets[c];
        }
        self.entries.clear();
        self.entries.resize(self.offsets[cell_count] as usize, 0);
        let mut cursor = std::mem::take(&mut self.cursor);
        cursor.clear();
        cursor.extend_from_slice(&self.offsets);
        for (i, b) in boxes.iter().enumerate() {
            let (lo, hi) = self.cell_span(b);
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let c = self.index(IVec3::new(x, y, z));
                        self.entries[cursor[c] as usize] = i as u32;
                        cursor[c] += 1;
                    }
                }
            }
        }
        self.cursor = cursor;
    }

    /// Calls `f` with every local face filed in a cell overlapping `query` (a face may come
    /// more than once; callers deduplicate).
    pub fn for_each_candidate(&self, query: &Aabb, mut f: impl FnMut(u32)) {
        if self.offsets.is_empty() {
            return;
        }
        self.for_each_cell(self.cell_span(query), |c, _| {
            for &e in &self.entries[self.offsets[c] as usize..self.offsets[c + 1] as usize] {
                f(e);
            }
        });
    }

    /// Calls `f` once with every local face filed in a cell overlapping `query` (`boxes` the
    /// boxes the grid was built from): a face is taken only in the lowest cell that both its
    /// box and the query cover, with no list to sort and deduplicate.
    pub fn for_each_face_once(&self, query: &Aabb, boxes: &[Aabb], mut f: impl FnMut(u32)) {
        if self.offsets.is_empty() {
            return;
        }
        let span = self.cell_span(query);
        self.for_each_cell(span, |c, at| {
            for &e in &self.entries[self.offsets[c] as usize..self.offsets[c + 1] as usize] {
                if self.cell_span(&boxes[e as usize]).0.max(span.0) == at {
                    f(e);
                }
            }
        });
    }

    /// Calls `f` with the index and coordinates of every cell of `span`.
    pub fn for_each_cell(&self, (lo, hi): (IVec3, IVec3), mut f: impl FnMut(usize, IVec3)) {
        if self.offsets.is_empty() {
            return;
        }
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let at = IVec3::new(x, y, z);
                    f(self.index(at), at);
                }
            }
        }
    }

    /// Whether `f` holds for some local face filed in a cell overlapping `query`; stops at the
    /// first.
    pub fn any_candidate(&self, query: &Aabb, mut f: impl FnMut(u32) -> bool) -> bool {
        if self.offsets.is_empty() {
            return false;
        }
        let (lo, hi) = self.cell_span(query);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let c = self.index(IVec3::new(x, y, z));
                    let cell =
                        &self.entries[self.offsets[c] as usize..self.offsets[c + 1] as usize];
                    if cell.iter().any(|&e| f(e)) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// The cells overlapping `b`, lowest and highest (clamped to the grid, as filing and
    /// queries are): also for callers that file more faces beside the grid's own.
    pub fn cell_span(&self, b: &Aabb) -> (IVec3, IVec3) {
        // Truncation is floor here: everything below the origin clamps to cell 0 anyway.
        let clamp = |p: Vec3| {
            ((p - self.origin) * self.inv_cell)
                .max(Vec3::ZERO)
                .as_ivec3()
                .min(self.dims - IVec3::ONE)
        };
        (clamp(b.min), clamp(b.max))
    }

    #[inline]
    fn index(&self, c: IVec3) -> usize {
        ((c.z * self.dims.y + c.y) * self.dims.x + c.x) as usize
    }
}
