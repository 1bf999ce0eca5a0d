//! The faces of a mesh near where a tool puts new geometry, filed in a dense grid: what the
//! new vertices are kept clear of and the new faces are tested against exactly.

use glam::Vec3;
use rayon::prelude::*;

use crate::collide::LocalFaceGrid;
use crate::geom::{
    Aabb, closest_point_on_triangle, point_triangle_distance_squared, triangles_intersect,
};
use crate::mesh::{LayerId, Mesh};

/// The live faces of a mesh whose boxes meet a region.
pub(super) struct Obstacles {
    /// The mesh's index of each face here.
    faces: Vec<u32>,
    triangles: Vec<[Vec3; 3]>,
    layers: Vec<LayerId>,
    boxes: Vec<Aabb>,
    grid: LocalFaceGrid,
}

impl Obstacles {
    /// The faces of `mesh` whose boxes meet `region`, in a grid of cell `cell`.
    pub(super) fn near(mesh: &Mesh, region: Aabb, cell: f32) -> Obstacles {
        let mut obstacles = Obstacles {
            faces: Vec::new(),
            triangles: Vec::new(),
            layers: Vec::new(),
            boxes: Vec::new(),
            grid: LocalFaceGrid::default(),
        };
        for f in 0..mesh.face_count() {
            if mesh.is_face_dead(f) {
                continue;
            }
            let tri = mesh.face_positions(f);
            let b = Aabb::of_points(&tri);
            if b.overlaps(&region) {
                obstacles.faces.push(f as u32);
                obstacles.triangles.push(tri);
                obstacles.layers.push(mesh.face_layers()[f]);
                obstacles.boxes.push(b);
            }
        }
        let bounds = obstacles
            .boxes
            .iter()
            .fold(Aabb::EMPTY, |a, b| a.including_box(b));
        if !bounds.is_empty() {
            obstacles.grid.build(&obstacles.boxes, bounds, cell);
        }
        obstacles
    }

    /// The nearest face within `reach` of `p` among those `counts` lets in: its layer and
    /// distance.
    pub(super) fn nearest_within(
        &self,
        p: Vec3,
        reach: f32,
        counts: impl Fn(LayerId) -> bool,
    ) -> Option<(LayerId, f32)> {
        let query = Aabb::of_points(&[p]).expanded(reach);
        let mut best: Option<(LayerId, f32)> = None;
        self.grid.for_each_candidate(&query, |i| {
            let i = i as usize;
            if !counts(self.layers[i]) || !self.boxes[i].within(p, reach) {
                return;
            }
            let [a, b, c] = self.triangles[i];
            let d2 = point_triangle_distance_squared(p, a, b, c);
            if d2 < reach * reach && best.is_none_or(|(_, d)| d2 < d * d) {
                best = Some((self.layers[i], d2.sqrt()));
            }
        });
        best
    }

    /// The face of `layer` nearest to `p` within `reach`, and its point nearest to `p`.
    pub(super) fn nearest_face(&self, p: Vec3, reach: f32, layer: LayerId) -> Option<(u32, Vec3)> {
        let query = Aabb::of_points(&[p]).expanded(reach);
        let mut best: Option<(u32, Vec3, f32)> = None;
        self.grid.for_each_candidate(&query, |i| {
            let i = i as usize;
            if self.layers[i] != layer || !self.boxes[i].within(p, reach) {
                return;
            }
            let [a, b, c] = self.triangles[i];
            let q = closest_point_on_triangle(p, a, b, c);
            let d2 = q.distance_squared(p);
            let better = best.is_none_or(|(f, _, d)| (d2, self.faces[i]) < (d, f));
            if d2 < reach * reach && better {
                best = Some((self.faces[i], q, d2));
            }
        });
        best.map(|(f, q, _)| (f, q))
    }

    /// Whether a face of `layer` lies within `reach` of `p` and nearer to `p` than to
    /// `start`: the surface ahead of a point walking away from `start` (a groove's far wall),
    /// not the one it left (whose faces around `start` are nearer to `start`).
    pub(super) fn own_surface_ahead(
        &self,
        p: Vec3,
        start: Vec3,
        reach: f32,
        layer: LayerId,
    ) -> bool {
        let query = Aabb::of_points(&[p]).expanded(reach);
        self.grid.any_candidate(&query, |i| {
            let i = i as usize;
            if self.layers[i] != layer || !self.boxes[i].within(p, reach) {
                return false;
            }
            let [a, b, c] = self.triangles[i];
            let d2 = point_triangle_distance_squared(p, a, b, c);
            d2 < reach * reach && d2 < point_triangle_distance_squared(start, a, b, c)
        })
    }

    /// How many pairs of one of `triangles` and a face here intersect (exact test).
    pub(super) fn intersecting_pairs(&self, triangles: &[[Vec3; 3]]) -> usize {
        triangles
            .par_iter()
            .map_init(Vec::new, |seen: &mut Vec<u32>, tri| {
                let b = Aabb::of_points(tri);
                seen.clear();
                self.grid.for_each_candidate(&b, |i| seen.push(i));
                seen.sort_unstable();
                seen.dedup();
                seen.iter()
                    .filter(|&&i| {
                        self.boxes[i as usize].overlaps(&b)
                            && triangles_intersect(*tri, self.triangles[i as usize])
                    })
                    .count()
            })
            .sum()
    }
}
