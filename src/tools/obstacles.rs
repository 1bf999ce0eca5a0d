//! The faces of a mesh near where a tool puts new geometry, filed in a dense grid: what the
//! new vertices are kept clear of and the new faces are tested against exactly.

use glam::Vec3;
use rayon::prelude::*;

use crate::collide::LocalFaceGrid;
use crate::geom::{
    Aabb, closest_point_on_triangle, point_triangle_distance_squared, triangles_intersect,
};
use crate::mesh::{LayerId, Mesh};

/// A face that a walk along a line passes near ([`Obstacles::passing`]): its index here,
/// its layer, and the stretch of the line's parameter within reach of its box.
#[derive(Clone, Copy, Debug)]
pub(super) struct Passing {
    pub face: u32,
    pub layer: LayerId,
    pub from: f32,
    pub to: f32,
}

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
        let (faces, boxes): (Vec<u32>, Vec<Aabb>) = (0..mesh.face_count())
            .into_par_iter()
            .filter(|&f| !mesh.is_face_dead(f))
            .map(|f| (f as u32, Aabb::of_points(&mesh.face_positions(f))))
            .filter(|(_, b)| b.overlaps(&region))
            .unzip();
        let mut obstacles = Obstacles {
            triangles: faces
                .par_iter()
                .map(|&f| mesh.face_positions(f as usize))
                .collect(),
            layers: faces
                .iter()
                .map(|&f| mesh.face_layers()[f as usize])
                .collect(),
            faces,
            boxes,
            grid: LocalFaceGrid::default(),
        };
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
        let mut best = None;
        self.grid.for_each_candidate(&query, |i| {
            self.keep_nearer(&mut best, i, (p, reach), &counts);
        });
        best
    }

    /// The faces here whose boxes come within `reach(layer)` of the segment `start + dir·t`,
    /// `t` in `span`, each once, into `passing`, with the stretch of `t` where the line does
    /// (`widest`: the largest reach). Every query of a walk along the segment then reads
    /// these few, with no grid.
    pub(super) fn passing(
        &self,
        (start, dir): (Vec3, Vec3),
        span: (f32, f32),
        (reach, widest): (impl Fn(LayerId) -> f32, f32),
        passing: &mut Vec<Passing>,
    ) {
        passing.clear();
        let ends = [start + dir * span.0, start + dir * span.1];
        let region = Aabb::of_points(&ends).expanded(widest);
        // Slack for the rounding of the slab test's divisions, relative to the coordinates.
        let slack = 1e-6 * region.min.abs().max(region.max.abs()).max_element();
        self.grid.for_each_face_once(&region, &self.boxes, |face| {
            let (bounds, layer) = (&self.boxes[face as usize], self.layers[face as usize]);
            if !bounds.overlaps(&region) {
                return;
            }
            let grown = bounds.expanded(reach(layer) * 1.001 + slack);
            let stretch = stretch_through(&grown, (start, dir));
            if let Some((from, to)) = stretch.filter(|&(from, to)| from <= span.1 && to >= span.0) {
                passing.push(Passing {
                    face,
                    layer,
                    from,
                    to,
                });
            }
        });
    }

    /// How many faces are here.
    #[cfg(test)]
    pub(super) fn len(&self) -> usize {
        self.faces.len()
    }

    /// Face `i`'s layer.
    #[cfg(test)]
    pub(super) fn layer(&self, i: u32) -> LayerId {
        self.layers[i as usize]
    }

    /// Face `i`'s distance from `p`, where it is within `reach`.
    pub(super) fn distance_within(&self, i: u32, p: Vec3, reach: f32) -> Option<f32> {
        self.distance_squared_within(i, p, reach).map(f32::sqrt)
    }

    /// Whether face `i` lies within `reach` of `p` and nearer to `p` than to `start`: the
    /// surface ahead of a point walking away from `start` (a groove's far wall), not the one
    /// it left (whose faces around `start` are nearer to `start`).
    pub(super) fn ahead(&self, i: u32, p: Vec3, start: Vec3, reach: f32) -> bool {
        let [a, b, c] = self.triangles[i as usize];
        self.distance_squared_within(i, p, reach)
            .is_some_and(|d2| d2 < point_triangle_distance_squared(start, a, b, c))
    }

    fn distance_squared_within(&self, i: u32, p: Vec3, reach: f32) -> Option<f32> {
        let i = i as usize;
        if !self.boxes[i].within(p, reach) {
            return None;
        }
        let [a, b, c] = self.triangles[i];
        let d2 = point_triangle_distance_squared(p, a, b, c);
        (d2 < reach * reach).then_some(d2)
    }

    /// Makes `best` face `i` where it lies nearer to `p` than `best`, within `reach`, and of a
    /// layer `counts` lets in.
    fn keep_nearer(
        &self,
        best: &mut Option<(LayerId, f32)>,
        i: u32,
        (p, reach): (Vec3, f32),
        counts: &impl Fn(LayerId) -> bool,
    ) {
        let layer = self.layers[i as usize];
        if !counts(layer) {
            return;
        }
        if let Some(d) = self.distance_within(i, p, reach)
            && best.is_none_or(|(_, nearest)| d < nearest)
        {
            *best = Some((layer, d));
        }
    }

    /// [`Obstacles::nearest_within`] among the faces `passing` names.
    pub(super) fn nearest_passing(
        &self,
        passing: &[Passing],
        (p, reach): (Vec3, f32),
        counts: impl Fn(LayerId) -> bool,
    ) -> Option<(LayerId, f32)> {
        let mut best = None;
        for near in passing {
            self.keep_nearer(&mut best, near.face, (p, reach), &counts);
        }
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

    /// How many pairs of one of `triangles` and a face here intersect (exact test).
    pub(super) fn intersecting_pairs(&self, triangles: &[[Vec3; 3]]) -> usize {
        triangles
            .par_iter()
            .map(|tri| {
                let b = Aabb::of_points(tri);
                let mut crossing = 0;
                self.grid.for_each_face_once(&b, &self.boxes, |i| {
                    let i = i as usize;
                    crossing += usize::from(
                        self.boxes[i].overlaps(&b) && triangles_intersect(*tri, self.triangles[i]),
                    );
                });
                crossing
            })
            .sum()
    }
}

/// Where the line `start + dir·t` runs through `bounds`: the `t` where it enters and leaves
/// (a slab test), or `None`.
fn stretch_through(bounds: &Aabb, (start, dir): (Vec3, Vec3)) -> Option<(f32, f32)> {
    let (mut from, mut to) = (f32::NEG_INFINITY, f32::INFINITY);
    for axis in 0..3 {
        let (lo, hi, s) = (bounds.min[axis], bounds.max[axis], start[axis]);
        if dir[axis] == 0.0 {
            if s < lo || s > hi {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo - s) / dir[axis], (hi - s) / dir[axis]);
        from = from.max(a.min(b));
        to = to.min(a.max(b));
    }
    (from <= to).then_some((from, to))
}
