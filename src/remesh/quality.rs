//! How even a mesh is and how near it stays to another, as `slayer remesh` reports a whole-mesh
//! remesh: edge lengths, smallest angles, valences, and the distance from the result to its
//! input (a one-sided Hausdorff estimate over sample points, in edge lengths).

use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::collide::LocalFaceGrid;
use crate::geom::{Aabb, closest_point_on_triangle};
use crate::mesh::Mesh;

/// The distribution of the smallest angle of a set of faces, in degrees.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct AngleSummary {
    pub faces: usize,
    pub p1: f64,
    pub p5: f64,
    pub median: f64,
    /// Share of faces whose smallest angle is below 20° and below 30°.
    pub below_20: f64,
    pub below_30: f64,
}

impl AngleSummary {
    pub fn of(triangles: impl Iterator<Item = [Vec3; 3]>) -> AngleSummary {
        let mut angles: Vec<f64> = triangles.map(smallest_angle_degrees).collect();
        if angles.is_empty() {
            return AngleSummary::default();
        }
        angles.sort_unstable_by(f64::total_cmp);
        let n = angles.len();
        let at = |q: f64| angles[((n - 1) as f64 * q).round() as usize];
        let share = |limit: f64| angles.partition_point(|&a| a < limit) as f64 / n as f64;
        AngleSummary {
            faces: n,
            p1: at(0.01),
            p5: at(0.05),
            median: at(0.5),
            below_20: share(20.0),
            below_30: share(30.0),
        }
    }

    /// The live faces of `mesh`.
    pub fn of_mesh(mesh: &Mesh) -> AngleSummary {
        AngleSummary::of(
            (0..mesh.face_count())
                .filter(|&f| !mesh.is_face_dead(f))
                .map(|f| mesh.face_positions(f)),
        )
    }
}

/// Smallest interior angle of a triangle, in degrees (0 for a degenerate one).
pub fn smallest_angle_degrees([a, b, c]: [Vec3; 3]) -> f64 {
    let angle = |p: Vec3, q: Vec3, r: Vec3| {
        let (u, v) = ((q - p).as_dvec3(), (r - p).as_dvec3());
        let denominator = u.length() * v.length();
        if denominator == 0.0 {
            0.0
        } else {
            (u.dot(v) / denominator)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees()
        }
    };
    angle(a, b, c).min(angle(b, c, a)).min(angle(c, a, b))
}

/// A mesh's evenness.
#[derive(Debug, Clone, Serialize)]
pub struct Quality {
    pub faces: usize,
    pub vertices: usize,
    pub mean_edge: f64,
    /// Edge length's coefficient of variation.
    pub edge_cv: f64,
    pub smallest_angle: AngleSummary,
    /// Interior vertices by valence, `(valence, count)` ascending, the last bucket holding
    /// [`VALENCE_BUCKETS`] and more; boundary vertices are left out.
    pub valences: Vec<(usize, usize)>,
    /// Share of the interior vertices of valence 6.
    pub valence_6: f64,
}

/// The valence from which `Quality::valences` counts together.
pub const VALENCE_BUCKETS: usize = 12;

impl Quality {
    pub fn of(mesh: &Mesh) -> Quality {
        let stats = mesh.edge_length_stats();
        let mut counts = vec![0usize; VALENCE_BUCKETS + 1];
        for v in 0..mesh.vertex_count() as u32 {
            if mesh.is_vertex_live(v) && !mesh.is_boundary_vertex(v) {
                counts[mesh.valence(v).min(VALENCE_BUCKETS)] += 1;
            }
        }
        let interior: usize = counts.iter().sum();
        Quality {
            faces: mesh.live_face_count(),
            vertices: mesh.live_vertex_count(),
            mean_edge: stats.mean,
            edge_cv: stats.coefficient_of_variation(),
            smallest_angle: AngleSummary::of_mesh(mesh),
            valence_6: counts[6] as f64 / interior.max(1) as f64,
            valences: counts
                .into_iter()
                .enumerate()
                .filter(|&(_, n)| n > 0)
                .collect(),
        }
    }
}

/// How far a mesh lies from a reference surface, over sample points (every vertex and every
/// face's centroid), in units of `unit` (the target edge length).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Distance {
    pub samples: usize,
    /// The one-sided Hausdorff estimate: the farthest sample's distance.
    pub max: f64,
    pub mean: f64,
}

/// The faces of a reference surface filed for nearest-point queries.
pub struct Surface {
    triangles: Vec<[Vec3; 3]>,
    grid: LocalFaceGrid,
    /// The first query radius (a quarter edge: most samples lie that near), doubled until a
    /// face is found within it.
    reach: f32,
    diagonal: f32,
}

impl Surface {
    /// `mesh`'s live faces, as they are now.
    pub fn of(mesh: &Mesh) -> Surface {
        let triangles: Vec<[Vec3; 3]> = (0..mesh.face_count())
            .filter(|&f| !mesh.is_face_dead(f))
            .map(|f| mesh.face_positions(f))
            .collect();
        let boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::of_points(t)).collect();
        let bounds = boxes.iter().fold(Aabb::EMPTY, |b, t| b.including_box(t));
        let edge = mesh.mean_edge_length().max(f32::MIN_POSITIVE);
        let mut grid = LocalFaceGrid::default();
        if !triangles.is_empty() {
            grid.build(&boxes, bounds, 1.5 * edge);
        }
        let diagonal = (bounds.max - bounds.min).length();
        Surface {
            triangles,
            grid,
            reach: 0.25 * edge,
            diagonal,
        }
    }

    /// The distance from `p` to the nearest face (infinite with no faces).
    pub fn distance(&self, p: Vec3) -> f32 {
        let mut radius = self.reach;
        loop {
            let query = Aabb::of_points(&[p]).expanded(radius);
            let mut best = f32::INFINITY;
            self.grid.for_each_candidate(&query, |i| {
                let [a, b, c] = self.triangles[i as usize];
                best = best.min(p.distance(closest_point_on_triangle(p, a, b, c)));
            });
            // A face farther than the radius may be missed, one within it is not.
            if best <= radius || radius > 2.0 * self.diagonal || !radius.is_finite() {
                return best;
            }
            radius *= 2.0;
        }
    }

    /// How far `mesh` lies from this surface, in units of `unit`.
    pub fn distance_of(&self, mesh: &Mesh, unit: f32) -> Distance {
        let vertices = (0..mesh.vertex_count() as u32)
            .filter(|&v| mesh.is_vertex_live(v))
            .map(|v| mesh.positions()[v as usize]);
        let centroids = (0..mesh.face_count())
            .filter(|&f| !mesh.is_face_dead(f))
            .map(|f| {
                let [a, b, c] = mesh.face_positions(f);
                (a + b + c) / 3.0
            });
        let samples: Vec<Vec3> = vertices.chain(centroids).collect();
        let distances: Vec<f64> = samples
            .par_iter()
            .map(|&p| self.distance(p) as f64 / unit as f64)
            .collect();
        let n = distances.len();
        Distance {
            samples: n,
            max: distances.iter().copied().fold(0.0, f64::max),
            mean: distances.iter().sum::<f64>() / n.max(1) as f64,
        }
    }
}
