//! The uniform grid stored as a hash table (sLayer §3 "Grid-Based Broad Phase", after Teschner
//! et al. 2003; docs/design.md, "Data"). Cell side = target edge length `L`; vertices, not triangles, are
//! inserted. Because edges stay near `L`, every face within distance `r` of a point has a vertex
//! within `r + longest edge`, so one vertex grid answers brush selection, the collision broad
//! phase, picking and the remesher's proximity checks.
//!
//! Cells live in a fixed-size table of buckets indexed by [`hash_cell`] (Teschner's scheme, the
//! same table the GPU kernels build). Each bucket holds an intrusive doubly linked list of its
//! vertices (`next`/`prev` per vertex) and each vertex remembers its cell, so insert, remove and
//! move are O(1) without allocating — the paper's "list of vertex-to-cell correspondences" with
//! reference swapping. Cells that hash to the same bucket share its list; queries filter by the
//! stored cell. The table has at least twice as many buckets as vertices and grows when needed.
//! Beside it the grid keeps which cells hold a vertex (`occupancy`): a box query probes only
//! those, in the order a walk over every cell would meet them.

mod hash;
mod occupancy;
mod query;

pub use hash::{CellKey, hash_cell};
pub use query::RayHit;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use crate::geom::Aabb;
use crate::mesh::{INVALID, Mesh};
use occupancy::Occupancy;

/// Cell coordinate of a vertex that is not in the grid.
const ABSENT: IVec3 = IVec3::new(i32::MIN, i32::MIN, i32::MIN);
/// Smallest bucket table.
const MIN_BUCKETS: usize = 1024;

/// A uniform grid over vertex positions, stored sparsely.
#[derive(Debug, Clone)]
pub struct SpatialHash {
    cell_size: f32,
    inv_cell_size: f32,
    /// First vertex of each bucket's list; the length is a power of two.
    heads: Vec<u32>,
    /// Per vertex: its cell, or `ABSENT`.
    cell_of: Vec<IVec3>,
    next: Vec<u32>,
    prev: Vec<u32>,
    len: usize,
    /// Bounds of every position ever inserted (never shrinks: a safe box for ray walks).
    bounds: Aabb,
    /// The cells holding a vertex, so that box queries skip the empty ones.
    occupied: Occupancy,
}

impl SpatialHash {
    /// An empty grid with room for `vertex_capacity` vertex indices.
    pub fn new(cell_size: f32, vertex_capacity: usize) -> Result<Self, GridError> {
        if !(cell_size.is_finite() && cell_size > 0.0 && (1.0 / cell_size).is_finite()) {
            return Err(GridError::InvalidCellSize(cell_size));
        }
        Ok(SpatialHash {
            cell_size,
            inv_cell_size: 1.0 / cell_size,
            heads: vec![INVALID; bucket_count_for(vertex_capacity)],
            // Room for the vertices remeshing will add (`crate::grow`).
            cell_of: crate::grow::filled_with_room(vertex_capacity, ABSENT),
            next: crate::grow::filled_with_room(vertex_capacity, INVALID),
            prev: crate::grow::filled_with_room(vertex_capacity, INVALID),
            len: 0,
            bounds: Aabb::EMPTY,
            occupied: Occupancy::default(),
        })
    }

    /// A grid holding every live vertex of `mesh`, with cells of side `cell_size`. Cells are
    /// computed in parallel; lists are linked in vertex order, so the result is deterministic.
    pub fn build(mesh: &Mesh, cell_size: f32) -> Result<Self, GridError> {
        let mut grid = SpatialHash::new(cell_size, mesh.vertex_count())?;
        let inv = grid.inv_cell_size;
        let corners = &mesh.adjacency().vertex_corner;
        let cells: Vec<IVec3> = mesh
            .positions()
            .par_iter()
            .enumerate()
            .map(|(v, p)| {
                if corners[v] != INVALID {
                    cell_coordinates(*p, inv)
                } else {
                    ABSENT
                }
            })
            .collect();
        let bounds = mesh
            .positions()
            .par_iter()
            .enumerate()
            .filter(|(v, _)| corners[*v] != INVALID)
            .map(|(_, p)| Aabb { min: *p, max: *p })
            .reduce(
                || Aabb::EMPTY,
                |a, b| Aabb {
                    min: a.min.min(b.min),
                    max: a.max.max(b.max),
                },
            );
        grid.occupied = Occupancy::of_cells(&cells, |c| c != ABSENT);
        for (v, cell) in cells.into_iter().enumerate() {
            if cell != ABSENT {
                grid.link(v as u32, cell);
                grid.len += 1;
            }
        }
        grid.bounds = bounds;
        Ok(grid)
    }

    pub fn cell_size(&self) -> f32 {
        self.cell_size
    }

    /// `1 / cell_size`, the factor both the CPU and the GPU use to find a cell (a multiply is
    /// correctly rounded everywhere; a divide is not on every GPU).
    pub fn inv_cell_size(&self) -> f32 {
        self.inv_cell_size
    }

    /// Number of vertices in the grid.
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Buckets in the table (a power of two).
    pub fn bucket_count(&self) -> usize {
        self.heads.len()
    }

    /// Number of non-empty cells (counted from the occupancy's masks, on demand).
    pub fn occupied_cells(&self) -> usize {
        self.occupied.count()
    }

    /// The most vertices filed in one cell (counted on demand).
    pub fn max_cell_occupancy(&self) -> usize {
        self.cell_counts()
            .into_iter()
            .map(|(_, n)| n)
            .max()
            .unwrap_or(0)
    }

    fn cell_counts(&self) -> Vec<(IVec3, usize)> {
        let mut cells: Vec<[i32; 3]> = self
            .cell_of
            .iter()
            .filter(|&&c| c != ABSENT)
            .map(|c| c.to_array())
            .collect();
        cells.par_sort_unstable();
        let mut counts: Vec<(IVec3, usize)> = Vec::new();
        for c in cells {
            match counts.last_mut() {
                Some((last, n)) if last.to_array() == c => *n += 1,
                _ => counts.push((IVec3::from_array(c), 1)),
            }
        }
        counts
    }

    /// Heap bytes held: the bucket table, the per-vertex links and the occupied cells.
    pub fn memory_bytes(&self) -> usize {
        let per_vertex = std::mem::size_of::<IVec3>() + 2 * std::mem::size_of::<u32>();
        self.heads.capacity() * std::mem::size_of::<u32>()
            + self.cell_of.capacity() * per_vertex
            + self.occupied.memory_bytes()
    }

    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The cell containing `p`. Coordinates saturate at the `i32` range (validated meshes stay
    /// far inside it).
    #[inline]
    pub fn cell_of_point(&self, p: Vec3) -> IVec3 {
        cell_coordinates(p, self.inv_cell_size)
    }

    /// The cell a vertex was filed under, if it is in the grid.
    pub fn cell_of_vertex(&self, vertex: u32) -> Option<IVec3> {
        let cell = *self.cell_of.get(vertex as usize)?;
        (cell != ABSENT).then_some(cell)
    }

    pub fn contains(&self, vertex: u32) -> bool {
        self.cell_of_vertex(vertex).is_some()
    }

    /// Files `vertex` at position `p`. O(1) amortized; a vertex already present is moved.
    pub fn insert(&mut self, vertex: u32, p: Vec3) {
        let v = vertex as usize;
        // Grown gently (an eighth at a time, `crate::grow`): doubling would copy and fill
        // all three arrays at the first vertex a stroke adds to a large mesh.
        crate::grow::grow_to(&mut self.cell_of, v + 1, ABSENT);
        crate::grow::grow_to(&mut self.next, v + 1, INVALID);
        crate::grow::grow_to(&mut self.prev, v + 1, INVALID);
        if self.cell_of[v] != ABSENT {
            self.move_to(vertex, p);
            return;
        }
        if 2 * (self.len + 1) > self.heads.len() {
            self.grow();
        }
        let cell = self.cell_of_point(p);
        self.link(vertex, cell);
        self.occupied.set(cell);
        self.len += 1;
        self.bounds = self.bounds.including(p);
    }

    /// Takes `vertex` out of the grid. O(1); absent vertices are ignored.
    pub fn remove(&mut self, vertex: u32) {
        if !self.contains(vertex) {
            return;
        }
        self.unfile(vertex);
        self.cell_of[vertex as usize] = ABSENT;
        self.len -= 1;
    }

    /// Refiles `vertex` at its new position `p`; nothing changes when it stays in its cell.
    pub fn move_to(&mut self, vertex: u32, p: Vec3) {
        let Some(old) = self.cell_of_vertex(vertex) else {
            self.insert(vertex, p);
            return;
        };
        self.bounds = self.bounds.including(p);
        let cell = self.cell_of_point(p);
        if cell == old {
            return;
        }
        self.unfile(vertex);
        self.link(vertex, cell);
        self.occupied.set(cell);
    }

    /// Takes `vertex` out of its bucket's list, and its cell out of the occupied ones if it
    /// was the cell's last vertex.
    fn unfile(&mut self, vertex: u32) {
        self.unlink(vertex);
        let cell = self.cell_of[vertex as usize];
        if self.cell_vertices(cell).next().is_none() {
            self.occupied.clear(cell);
        }
    }

    /// Vertices filed in one cell.
    pub fn cell_vertices(&self, cell: IVec3) -> CellIter<'_> {
        CellIter {
            grid: self,
            cell,
            current: self.heads[self.bucket(cell)],
        }
    }

    #[inline]
    fn bucket(&self, cell: IVec3) -> usize {
        hash_cell(cell, self.heads.len() as u32) as usize
    }

    /// Doubles the bucket table and relinks every vertex.
    fn grow(&mut self) {
        self.heads = vec![INVALID; self.heads.len() * 2];
        for v in 0..self.cell_of.len() {
            let cell = self.cell_of[v];
            if cell != ABSENT {
                self.link(v as u32, cell);
            }
        }
    }

    fn link(&mut self, vertex: u32, cell: IVec3) {
        let v = vertex as usize;
        let bucket = self.bucket(cell);
        let head = self.heads[bucket];
        self.next[v] = head;
        self.prev[v] = INVALID;
        if head != INVALID {
            self.prev[head as usize] = vertex;
        }
        self.heads[bucket] = vertex;
        self.cell_of[v] = cell;
    }

    fn unlink(&mut self, vertex: u32) {
        let v = vertex as usize;
        let (prev, next) = (self.prev[v], self.next[v]);
        if next != INVALID {
            self.prev[next as usize] = prev;
        }
        if prev != INVALID {
            self.next[prev as usize] = next;
        } else {
            let bucket = self.bucket(self.cell_of[v]);
            self.heads[bucket] = next;
        }
        self.next[v] = INVALID;
        self.prev[v] = INVALID;
    }

    /// Checks the bucket lists against the per-vertex cells (for tests).
    pub fn check_consistency(&self, positions: &[Vec3]) -> Result<(), String> {
        let mut seen = 0usize;
        for (bucket, &head) in self.heads.iter().enumerate() {
            let mut prev = INVALID;
            let mut v = head;
            while v != INVALID {
                let cell = self.cell_of[v as usize];
                if cell == ABSENT || self.bucket(cell) != bucket {
                    return Err(format!(
                        "vertex {v} listed in bucket {bucket} but filed in {cell}"
                    ));
                }
                if self.prev[v as usize] != prev {
                    return Err(format!("vertex {v}: back link broken"));
                }
                if let Some(p) = positions.get(v as usize)
                    && self.cell_of_point(*p) != cell
                {
                    return Err(format!("vertex {v} at {p} is filed in stale cell {cell}"));
                }
                seen += 1;
                prev = v;
                v = self.next[v as usize];
            }
        }
        if seen != self.len {
            return Err(format!("{seen} vertices listed, {} counted", self.len));
        }
        let cells = self.cell_counts();
        if let Some((cell, _)) = cells.iter().find(|(c, _)| !self.occupied.is_set(*c)) {
            return Err(format!(
                "cell {cell} holds a vertex but is not marked occupied"
            ));
        }
        if self.occupied_cells() != cells.len() {
            return Err(format!(
                "{} cells marked occupied, {} hold a vertex",
                self.occupied_cells(),
                cells.len()
            ));
        }
        Ok(())
    }
}

/// Buckets for `vertices` vertices: a power of two, at least twice as many.
fn bucket_count_for(vertices: usize) -> usize {
    (2 * vertices).next_power_of_two().max(MIN_BUCKETS)
}

/// Why a grid could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    #[error("grid cell size must be a positive finite length, got {0}")]
    InvalidCellSize(f32),
}

/// The cell of `p` for a grid with `1 / cell_size = inv_cell_size` (mirrored by the GPU kernels).
#[inline]
pub fn cell_coordinates(p: Vec3, inv_cell_size: f32) -> IVec3 {
    let c = p * inv_cell_size;
    IVec3::new(floor_to_i32(c.x), floor_to_i32(c.y), floor_to_i32(c.z))
}

/// `x.floor() as i32` without a libm call: truncate, then step down for negative non-integers.
/// `as` saturates (and maps NaN to 0), so absurd input cannot wrap around.
#[inline]
fn floor_to_i32(x: f32) -> i32 {
    let t = x as i32;
    if (t as f32) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// Iterator over the vertices of one cell (its bucket's list, filtered by cell).
pub struct CellIter<'a> {
    grid: &'a SpatialHash,
    cell: IVec3,
    current: u32,
}

impl Iterator for CellIter<'_> {
    type Item = u32;

    fn next(&mut self) -> Option<u32> {
        while self.current != INVALID {
            let v = self.current;
            self.current = self.grid.next[v as usize];
            if self.grid.cell_of[v as usize] == self.cell {
                return Some(v);
            }
        }
        None
    }
}
