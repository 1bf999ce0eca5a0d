//! Queries on the grid: brush selection (sphere), the collision broad phase (faces near a point)
//! and picking (first face along a ray).

use glam::{IVec3, Vec3};
use rustc_hash::FxHashSet;

use super::SpatialHash;
use crate::geom::{Ray, point_triangle_distance_squared, ray_triangle};
use crate::mesh::VertexFaces;

/// A face hit by a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    pub face: u32,
    pub t: f32,
    pub point: Vec3,
}

impl SpatialHash {
    /// Calls `f` for every vertex filed in a cell overlapping the box `[lo, hi]`.
    pub fn for_each_in_box(&self, lo: Vec3, hi: Vec3, mut f: impl FnMut(u32)) {
        let (a, b) = (self.cell_of_point(lo), self.cell_of_point(hi));
        // Visiting empty cells costs a hash lookup each; a box far larger than the occupied
        // region is clipped to the grid's bounds first.
        let (bl, bh) = (
            self.cell_of_point(self.bounds.min),
            self.cell_of_point(self.bounds.max),
        );
        let (a, b) = (a.max(bl), b.min(bh));
        if a.cmpgt(b).any() {
            return;
        }
        let cells = (b - a + IVec3::ONE).as_i64vec3();
        if cells.x * cells.y * cells.z > 4 * self.cell_of.len() as i64 {
            // Cheaper to scan the vertices than to probe the box cell by cell.
            for (v, cell) in self.cell_of.iter().enumerate() {
                if *cell != super::ABSENT && cell.cmpge(a).all() && cell.cmple(b).all() {
                    f(v as u32);
                }
            }
            return;
        }
        self.occupied
            .for_each_occupied(a, b, |cell| self.cell_vertices(cell).for_each(&mut f));
    }

    /// Brush selection: every vertex with `|p - center| ≤ radius`, appended to `out`.
    pub fn vertices_in_sphere(
        &self,
        positions: &[Vec3],
        center: Vec3,
        radius: f32,
        out: &mut Vec<u32>,
    ) {
        let r2 = radius * radius;
        self.for_each_in_box(center - radius, center + radius, |v| {
            if positions[v as usize].distance_squared(center) <= r2 {
                out.push(v);
            }
        });
    }

    /// Broad phase: faces incident to a vertex in a cell overlapping the box of radius
    /// `radius + max_edge` around `point`. With `max_edge` at least the longest edge, this is a
    /// superset of the faces within `radius` of `point`. Each face appears once.
    pub fn candidate_faces(
        &self,
        vertex_faces: &VertexFaces,
        point: Vec3,
        radius: f32,
        max_edge: f32,
        out: &mut Vec<u32>,
    ) {
        let reach = radius + max_edge;
        let start = out.len();
        self.for_each_in_box(point - reach, point + reach, |v| {
            out.extend_from_slice(vertex_faces.of(v));
        });
        let tail = &mut out[start..];
        tail.sort_unstable();
        let unique = dedup_sorted(tail);
        out.truncate(start + unique);
    }

    /// Faces whose closest point lies within `radius` of `point` (exact distance), given that
    /// no edge is longer than `max_edge`.
    pub fn faces_within(
        &self,
        positions: &[Vec3],
        faces: &[[u32; 3]],
        vertex_faces: &VertexFaces,
        point: Vec3,
        radius: f32,
        max_edge: f32,
    ) -> Vec<u32> {
        let mut candidates = Vec::new();
        self.candidate_faces(vertex_faces, point, radius, max_edge, &mut candidates);
        let r2 = radius * radius;
        candidates.retain(|&f| {
            let [a, b, c] = faces[f as usize].map(|v| positions[v as usize]);
            point_triangle_distance_squared(point, a, b, c) <= r2
        });
        candidates
    }

    /// Picking: the first face along `ray` (smallest `t`, ties to the lower face index), given
    /// that no edge is longer than `max_edge`.
    ///
    /// Walks the cells the ray crosses (Amanatides–Woo). A face hit at `t` has a vertex within
    /// `max_edge` of the hit point, so each crossed cell's neighbourhood of that reach is
    /// searched; the walk stops once a cell starts beyond the best hit.
    pub fn first_hit(
        &self,
        positions: &[Vec3],
        faces: &[[u32; 3]],
        vertex_faces: &VertexFaces,
        ray: &Ray,
        max_edge: f32,
    ) -> Option<RayHit> {
        if self.is_empty() || !ray.direction.is_finite() || ray.direction == Vec3::ZERO {
            return None;
        }
        let reach = max_edge.max(0.0);
        let region = self.bounds.expanded(reach + self.cell_size);
        let (t_enter, t_exit) = slab_interval(ray, region.min, region.max)?;
        let t_enter = t_enter.max(0.0);
        if t_enter > t_exit {
            return None;
        }
        // One extra ring absorbs rounding in the walk's cell arithmetic.
        let ring = (reach * self.inv_cell_size).ceil() as i32 + 1;
        let mut visited_cells: FxHashSet<IVec3> = FxHashSet::default();
        let mut tested: FxHashSet<u32> = FxHashSet::default();
        let mut best: Option<RayHit> = None;

        let mut walk = CellWalk::new(ray, t_enter, self.cell_size, self.inv_cell_size);
        while walk.t_cell_start <= t_exit {
            if best.is_some_and(|b| walk.t_cell_start > b.t) {
                break;
            }
            for dz in -ring..=ring {
                for dy in -ring..=ring {
                    for dx in -ring..=ring {
                        let cell = walk.cell + IVec3::new(dx, dy, dz);
                        if !visited_cells.insert(cell) {
                            continue;
                        }
                        for v in self.cell_vertices(cell) {
                            for &f in vertex_faces.of(v) {
                                if !tested.insert(f) {
                                    continue;
                                }
                                let [a, b, c] = faces[f as usize].map(|i| positions[i as usize]);
                                if let Some(t) = ray_triangle(ray, a, b, c) {
                                    let better = match best {
                                        None => true,
                                        Some(h) => t < h.t || (t == h.t && f < h.face),
                                    };
                                    if better {
                                        best = Some(RayHit {
                                            face: f,
                                            t,
                                            point: ray.at(t),
                                        });
                                    }
                                }
                            }
                        }
                    }
                }
            }
            if !walk.step() {
                break;
            }
        }
        best
    }
}

/// Keeps the first of each run of equal values; returns how many remain.
fn dedup_sorted(values: &mut [u32]) -> usize {
    if values.is_empty() {
        return 0;
    }
    let mut kept = 1;
    for i in 1..values.len() {
        if values[i] != values[kept - 1] {
            values[kept] = values[i];
            kept += 1;
        }
    }
    kept
}

/// `[t_enter, t_exit]` of the ray inside a box, if it meets it.
fn slab_interval(ray: &Ray, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
    let mut t0 = f32::NEG_INFINITY;
    let mut t1 = f32::INFINITY;
    for axis in 0..3 {
        let o = ray.origin[axis];
        let d = ray.direction[axis];
        if d == 0.0 {
            if o < lo[axis] || o > hi[axis] {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo[axis] - o) / d, (hi[axis] - o) / d);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1).then_some((t0, t1))
}

/// Amanatides–Woo traversal of grid cells along a ray.
struct CellWalk {
    cell: IVec3,
    step: IVec3,
    t_max: Vec3,
    t_delta: Vec3,
    t_cell_start: f32,
}

impl CellWalk {
    fn new(ray: &Ray, t_start: f32, cell_size: f32, inv_cell_size: f32) -> Self {
        let p = ray.at(t_start);
        let cell = super::cell_coordinates(p, inv_cell_size);
        let mut step = IVec3::ZERO;
        let mut t_max = Vec3::splat(f32::INFINITY);
        let mut t_delta = Vec3::splat(f32::INFINITY);
        for axis in 0..3 {
            let d = ray.direction[axis];
            if d > 0.0 {
                step[axis] = 1;
                let boundary = (cell[axis] as f32 + 1.0) * cell_size;
                t_max[axis] = t_start + (boundary - p[axis]) / d;
                t_delta[axis] = cell_size / d;
            } else if d < 0.0 {
                step[axis] = -1;
                let boundary = cell[axis] as f32 * cell_size;
                t_max[axis] = t_start + (boundary - p[axis]) / d;
                t_delta[axis] = -cell_size / d;
            }
        }
        CellWalk {
            cell,
            step,
            t_max,
            t_delta,
            t_cell_start: t_start,
        }
    }

    /// Moves to the next cell; false when the ray cannot advance.
    fn step(&mut self) -> bool {
        let axis = if self.t_max.x <= self.t_max.y && self.t_max.x <= self.t_max.z {
            0
        } else if self.t_max.y <= self.t_max.z {
            1
        } else {
            2
        };
        if !self.t_max[axis].is_finite() {
            return false;
        }
        self.t_cell_start = self.t_max[axis];
        self.cell[axis] += self.step[axis];
        self.t_max[axis] += self.t_delta[axis];
        true
    }
}
