//! The uniform grid stored as a hash table (sLayer §3 "Grid-Based Broad Phase", after Teschner
//! et al. 2003; DESIGN §2). Cell side = target edge length `L`; vertices, not triangles, are
//! inserted. Because edges stay near `L`, every face within distance `r` of a point has a vertex
//! within `r + longest edge`, so one vertex grid answers brush selection, the collision broad
//! phase, picking and the remesher's proximity checks.
//!
//! Each cell holds an intrusive doubly linked list of its vertices (`next`/`prev` per vertex) and
//! each vertex remembers its cell, so insert, remove and move are O(1) without allocating — the
//! paper's "list of vertex-to-cell correspondences" with reference swapping.

mod hash;
mod query;

pub use hash::{CellKey, hash_cell};

use glam::{IVec3, Vec3};
use rustc_hash::FxHashMap;

use crate::geom::Aabb;
use crate::mesh::{INVALID, Mesh};

/// Why a grid could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    #[error("grid cell size must be a positive finite length, got {0}")]
    InvalidCellSize(f32),
}

/// Cell coordinate of a vertex that is not in the grid.
const ABSENT: IVec3 = IVec3::new(i32::MIN, i32::MIN, i32::MIN);

/// A uniform grid over vertex positions, stored sparsely.
#[derive(Debug, Clone)]
pub struct SpatialHash {
    cell_size: f32,
    inv_cell_size: f32,
    /// First vertex of each non-empty cell.
    heads: FxHashMap<IVec3, u32>,
    /// Per vertex: its cell, or `ABSENT`.
    cell_of: Vec<IVec3>,
    next: Vec<u32>,
    prev: Vec<u32>,
    len: usize,
    /// Bounds of every position ever inserted (never shrinks: a safe box for ray walks).
    bounds: Aabb,
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
            heads: FxHashMap::default(),
            cell_of: vec![ABSENT; vertex_capacity],
            next: vec![INVALID; vertex_capacity],
            prev: vec![INVALID; vertex_capacity],
            len: 0,
            bounds: Aabb::EMPTY,
        })
    }

    /// A grid holding every live vertex of `mesh`, with cells of side `cell_size`.
    pub fn build(mesh: &Mesh, cell_size: f32) -> Result<Self, GridError> {
        let mut grid = SpatialHash::new(cell_size, mesh.vertex_count())?;
        grid.heads.reserve(mesh.vertex_count());
        for (v, p) in mesh.positions().iter().enumerate() {
            if mesh.adjacency().vertex_corner[v] != INVALID {
                grid.insert(v as u32, *p);
            }
        }
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

    /// Number of non-empty cells.
    pub fn occupied_cells(&self) -> usize {
        self.heads.len()
    }

    /// Heap bytes held: the per-vertex links and the cell table (keys, heads, control bytes).
    pub fn memory_bytes(&self) -> usize {
        let per_vertex = std::mem::size_of::<IVec3>() + 2 * std::mem::size_of::<u32>();
        let per_cell = std::mem::size_of::<(IVec3, u32)>() + 1;
        self.cell_of.capacity() * per_vertex + self.heads.capacity() * per_cell
    }

    /// The most vertices filed in one cell.
    pub fn max_cell_occupancy(&self) -> usize {
        self.heads
            .keys()
            .map(|&cell| self.cell_vertices(cell).count())
            .max()
            .unwrap_or(0)
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

    /// Files `vertex` at position `p`. O(1); a vertex already present is moved.
    pub fn insert(&mut self, vertex: u32, p: Vec3) {
        let v = vertex as usize;
        if v >= self.cell_of.len() {
            let n = (v + 1).max(self.cell_of.len() * 2);
            self.cell_of.resize(n, ABSENT);
            self.next.resize(n, INVALID);
            self.prev.resize(n, INVALID);
        }
        if self.cell_of[v] != ABSENT {
            self.move_to(vertex, p);
            return;
        }
        self.link(vertex, self.cell_of_point(p));
        self.len += 1;
        self.bounds = self.bounds.including(p);
    }

    /// Takes `vertex` out of the grid. O(1); absent vertices are ignored.
    pub fn remove(&mut self, vertex: u32) {
        if !self.contains(vertex) {
            return;
        }
        self.unlink(vertex);
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
        self.unlink(vertex);
        self.link(vertex, cell);
    }

    /// Vertices filed in one cell.
    pub fn cell_vertices(&self, cell: IVec3) -> CellIter<'_> {
        CellIter {
            grid: self,
            current: self.heads.get(&cell).copied().unwrap_or(INVALID),
        }
    }

    fn link(&mut self, vertex: u32, cell: IVec3) {
        let v = vertex as usize;
        let head = self.heads.entry(cell).or_insert(INVALID);
        self.next[v] = *head;
        self.prev[v] = INVALID;
        if *head != INVALID {
            self.prev[*head as usize] = vertex;
        }
        *head = vertex;
        self.cell_of[v] = cell;
    }

    fn unlink(&mut self, vertex: u32) {
        let v = vertex as usize;
        let cell = self.cell_of[v];
        let (prev, next) = (self.prev[v], self.next[v]);
        if next != INVALID {
            self.prev[next as usize] = prev;
        }
        if prev != INVALID {
            self.next[prev as usize] = next;
        } else if next == INVALID {
            self.heads.remove(&cell);
        } else {
            self.heads.insert(cell, next);
        }
        self.next[v] = INVALID;
        self.prev[v] = INVALID;
    }

    /// Checks the linked lists against the per-vertex cells (for tests).
    pub fn check_consistency(&self, positions: &[Vec3]) -> Result<(), String> {
        let mut seen = 0usize;
        for (&cell, &head) in &self.heads {
            let mut prev = INVALID;
            let mut v = head;
            while v != INVALID {
                if self.cell_of[v as usize] != cell {
                    return Err(format!(
                        "vertex {v} listed in {cell} but filed in {}",
                        self.cell_of[v as usize]
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
        Ok(())
    }
}

/// The cell of `p` for a grid with `1 / cell_size = inv_cell_size` (mirrored by the GPU kernels).
#[inline]
pub fn cell_coordinates(p: Vec3, inv_cell_size: f32) -> IVec3 {
    let c = (p * inv_cell_size).floor();
    // `as` saturates (and maps NaN to 0), so absurd input can't wrap around.
    IVec3::new(c.x as i32, c.y as i32, c.z as i32)
}

/// Iterator over the vertices of one cell.
pub struct CellIter<'a> {
    grid: &'a SpatialHash,
    current: u32,
}

impl Iterator for CellIter<'_> {
    type Item = u32;

    fn next(&mut self) -> Option<u32> {
        if self.current == INVALID {
            return None;
        }
        let v = self.current;
        self.current = self.grid.next[v as usize];
        Some(v)
    }
}
