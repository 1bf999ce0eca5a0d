//! The faces around one step (its [`Region`]), gathered through the grid and filed in a local
//! face grid, with the per-thread scratch the searches over it use: the ground both phases of
//! the collision response stand on (the proximity clamp, `super::response`; the exact
//! backstop, `super::backstop`).

use glam::Vec3;
use rayon::prelude::*;

use super::state::StrokeState;
use super::{LocalFaceGrid, Stamps};
use crate::geom::Aabb;
use crate::mesh::{INVALID, Mesh};

/// A step's moves: the selection, each selected vertex's target, and per vertex its index in
/// the selection (`INVALID` for the others).
pub type StepMoves<'a> = (&'a [(u32, f32)], &'a [Vec3], &'a [u32]);

/// Per-thread scratch: the faces a query has met, a ring, a candidate list.
#[derive(Default)]
pub struct Scratch {
    seen: Stamps,
    pub(super) ring: Vec<u32>,
    pub(super) nearby: Vec<u32>,
}

/// Maps `f` over `items`, in parallel or not, with per-thread scratch.
pub(super) fn map_with_scratch<T: Send, I: Sync>(
    parallel: bool,
    items: &[I],
    f: impl Fn(&mut Scratch, &I) -> T + Sync + Send,
) -> Vec<T> {
    if parallel {
        items
            .par_iter()
            .map_init(Scratch::default, |s, item| f(s, item))
            .collect()
    } else {
        let mut scratch = Scratch::default();
        items.iter().map(|item| f(&mut scratch, item)).collect()
    }
}

/// The faces around one step: everything that could come within the collision distance of a
/// moving vertex, or cross a moving face. Kept in the pipeline between steps so its buffers are
/// reused.
#[derive(Default)]
pub struct Region {
    pub(super) faces: Vec<u32>,
    /// Per local face: box of its old and target positions.
    pub(super) boxes: Vec<Aabb>,
    grid: LocalFaceGrid,
    use_grid: bool,
    vertices: Vec<u32>,
    /// Mesh faces already in `faces`, and their index there.
    gathered: Stamps,
    local_index: Vec<u32>,
}

impl Region {
    /// Collects the faces around the step's moves (public so that `tests/gpu_parity/` can
    /// check the GPU proximity mirror against [`pull_back`](super::pull_back)).
    pub fn gather(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        selection: &[(u32, f32)],
        targets: &[Vec3],
        target_of: &[u32],
    ) {
        let positions = mesh.positions();
        let mut bounds = Aabb::EMPTY;
        for (&(v, _), &q) in selection.iter().zip(targets) {
            bounds = bounds.including(positions[v as usize]).including(q);
        }
        // A face within d of a moving point has a vertex within d + longest edge; a face that
        // crosses a moving face has a vertex within two longest edges of the moving vertex.
        let reach = state.collision_distance + 2.0 * state.max_edge;
        let region = bounds.expanded(reach);
        self.vertices.clear();
        match state.grid {
            Some(grid) => {
                let vertices = &mut self.vertices;
                grid.for_each_in_box(region.min, region.max, |v| vertices.push(v));
            }
            None => self
                .vertices
                .extend((0..mesh.vertex_count() as u32).filter(|&v| {
                    let p = positions[v as usize];
                    mesh.adjacency().vertex_corner[v as usize] != INVALID
                        && p.cmpge(region.min).all()
                        && p.cmple(region.max).all()
                })),
        }
        // Faces of those vertices, each once. Their order does not matter: every result below
        // is a minimum or a sorted set.
        self.gathered.start(mesh.face_count());
        self.local_index
            .resize(mesh.face_count().max(self.local_index.len()), 0);
        self.faces.clear();
        for &v in &self.vertices {
            for f in mesh.faces_around(v) {
                if self.gathered.insert(f as usize) {
                    self.local_index[f as usize] = self.faces.len() as u32;
                    self.faces.push(f);
                }
            }
        }
        self.boxes.clear();
        self.boxes.extend(self.faces.iter().map(|&f| {
            mesh.faces()[f as usize].iter().fold(Aabb::EMPTY, |b, &v| {
                let p = positions[v as usize];
                let slot = target_of[v as usize];
                let b = b.including(p);
                if slot == INVALID {
                    b
                } else {
                    b.including(targets[slot as usize])
                }
            })
        }));
        self.use_grid = state.grid.is_some();
        if let Some(g) = state.grid {
            self.grid
                .build(&self.boxes, region, LOCAL_CELL_EDGES * g.cell_size());
        }
    }

    /// Index of a mesh face in this region, if it is in it.
    pub(super) fn local(&self, face: u32) -> Option<usize> {
        self.gathered
            .contains(face as usize)
            .then(|| self.local_index[face as usize] as usize)
    }

    /// Local faces whose box overlaps `query`, each once.
    pub(super) fn candidates(&self, query: &Aabb, scratch: &mut Scratch, mut f: impl FnMut(usize)) {
        if self.use_grid {
            scratch.seen.start(self.faces.len());
            self.grid.for_each_candidate(query, |local| {
                if scratch.seen.insert(local as usize) && self.boxes[local as usize].overlaps(query)
                {
                    f(local as usize);
                }
            });
        } else {
            for (local, b) in self.boxes.iter().enumerate() {
                if b.overlaps(query) {
                    f(local);
                }
            }
        }
    }
}

/// Cell side of the per-step face grid, in edge lengths: a face box then covers one to two
/// cells per axis and a proximity query a handful.
const LOCAL_CELL_EDGES: f32 = 1.5;

/// Where vertex `v` was at the step's start: `before` for a selected one (through
/// `target_of`), its position for the others.
pub(super) fn start_position(mesh: &Mesh, v: u32, target_of: &[u32], before: &[Vec3]) -> Vec3 {
    match target_of[v as usize] {
        INVALID => mesh.positions()[v as usize],
        slot => before[slot as usize],
    }
}

pub(super) fn triangle(mesh: &Mesh, f: u32) -> [Vec3; 3] {
    mesh.face_positions(f as usize)
}
