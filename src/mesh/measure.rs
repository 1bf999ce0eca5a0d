//! Edge lengths, normals and bounds: the measurements every later stage leans on. The grid's cell
//! size is the mean edge length (sLayer's "edge length assumption").

use glam::Vec3;
use rayon::prelude::*;

use crate::geom;

use super::{INVALID, Mesh, face_of, next, prev};

/// Length statistics over the unique edges of the live faces.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EdgeLengthStats {
    pub edges: usize,
    pub mean: f64,
    pub std_dev: f64,
    pub min: f64,
    pub max: f64,
}

impl EdgeLengthStats {
    /// Coefficient of variation (standard deviation over mean), 0 for an empty mesh.
    pub fn coefficient_of_variation(&self) -> f64 {
        if self.mean > 0.0 {
            self.std_dev / self.mean
        } else {
            0.0
        }
    }
}

impl Mesh {
    /// Calls `f(a, b)` once per undirected edge of the live faces.
    pub fn for_each_edge(&self, mut f: impl FnMut(u32, u32)) {
        let opposite = &self.adjacency.opposite;
        for c in 0..(self.faces.len() * 3) as u32 {
            let o = opposite[c as usize];
            if self.faces[face_of(c) as usize][0] == INVALID || (o != INVALID && o < c) {
                continue;
            }
            f(self.corner_vertex(next(c)), self.corner_vertex(prev(c)));
        }
    }

    /// Unique edges of the live faces as vertex pairs.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut edges = Vec::with_capacity(self.faces.len() * 3 / 2 + 16);
        self.for_each_edge(|a, b| edges.push([a, b]));
        edges
    }

    /// The longest edge of the live faces.
    pub fn longest_edge(&self) -> f32 {
        (0..self.face_count())
            .into_par_iter()
            .filter(|&f| !self.is_face_dead(f))
            .map(|f| {
                let [a, b, c] = self.face_positions(f);
                a.distance(b).max(b.distance(c)).max(c.distance(a))
            })
            .reduce(|| 0.0, f32::max)
    }

    /// Mean, spread and range of edge lengths (f64 sums, so a million edges lose nothing).
    pub fn edge_length_stats(&self) -> EdgeLengthStats {
        let lengths: Vec<f64> = self
            .edges()
            .par_iter()
            .map(|&[a, b]| {
                (self.positions[a as usize].as_dvec3() - self.positions[b as usize].as_dvec3())
                    .length()
            })
            .collect();
        if lengths.is_empty() {
            return EdgeLengthStats::default();
        }
        let n = lengths.len() as f64;
        let mean = lengths.par_iter().sum::<f64>() / n;
        let variance = lengths
            .par_iter()
            .map(|l| (l - mean) * (l - mean))
            .sum::<f64>()
            / n;
        let min = lengths
            .par_iter()
            .copied()
            .reduce(|| f64::INFINITY, f64::min);
        let max = lengths
            .par_iter()
            .copied()
            .reduce(|| f64::NEG_INFINITY, f64::max);
        EdgeLengthStats {
            edges: lengths.len(),
            mean,
            std_dev: variance.sqrt(),
            min,
            max,
        }
    }

    /// Mean length of the unique edges of the live faces (0 for an empty mesh).
    pub fn mean_edge_length(&self) -> f32 {
        self.edge_length_stats().mean as f32
    }

    /// Recomputes the normals of `moved` (vertices on faces, each once) and of their
    /// neighbours that are not `moved`, whose faces turned with them; returns those
    /// neighbours, ascending. Each moved vertex lists its ring right after its own fan, while
    /// the fan's corners are still in cache, on every core: a serial walk of the rings first
    /// cost nearly as much as the normals (the 1M plane's draws).
    pub fn recompute_normals_around(
        &mut self,
        moved: &[u32],
        is_moved: impl Fn(u32) -> bool + Sync,
    ) -> Vec<u32> {
        const CHUNK: usize = 512;
        let parts: Vec<(Vec<Vec3>, Vec<u32>)> = moved
            .par_chunks(CHUNK)
            .map(|chunk| {
                let (mut normals, mut still) = (Vec::with_capacity(chunk.len()), Vec::new());
                for &v in chunk {
                    normals.push(self.area_weighted_normal(v));
                    still.extend(self.ring(v).filter(|&w| !is_moved(w)));
                }
                (normals, still)
            })
            .collect();
        let mut rim = Vec::new();
        for (chunk, (normals, still)) in moved.chunks(CHUNK).zip(parts) {
            for (&v, n) in chunk.iter().zip(normals) {
                self.normals[v as usize] = n;
            }
            rim.extend(still);
        }
        rim.sort_unstable();
        rim.dedup();
        self.recompute_normals_at(&rim);
        rim
    }

    /// Area-weighted vertex normals of the whole mesh.
    pub fn recompute_normals(&mut self) {
        let normals: Vec<Vec3> = (0..self.vertex_count() as u32)
            .into_par_iter()
            .map(|v| self.area_weighted_normal(v))
            .collect();
        self.normals = normals;
    }

    /// Recomputes the normals of the given vertices only (after a brush step).
    pub fn recompute_normals_at(&mut self, vertices: &[u32]) {
        let updated: Vec<Vec3> = vertices
            .par_iter()
            .map(|&v| self.area_weighted_normal(v))
            .collect();
        for (&v, n) in vertices.iter().zip(updated) {
            self.normals[v as usize] = n;
        }
    }

    /// The incident faces' cross products, each seen from the vertex, summed in an order-free
    /// way ([`geom::fan_normal`]: a mirrored mesh gets mirrored normals to the bit) and
    /// normalized; +Z where that sum vanishes (a vertex of only degenerate faces) so that
    /// normals are always finite.
    fn area_weighted_normal(&self, vertex: u32) -> Vec3 {
        if self.adjacency.vertex_corner[vertex as usize] == INVALID {
            return Vec3::Z;
        }
        geom::fan_normal(|| {
            self.faces_around(vertex).map(move |face| {
                geom::corner_cross(self.faces[face as usize], vertex, |i| {
                    self.positions[i as usize]
                })
            })
        })
    }

    /// Unit normal of a face (zero for a degenerate one).
    pub fn face_normal(&self, face: usize) -> Vec3 {
        let [a, b, c] = self.face_positions(face);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// Axis-aligned bounds of the live vertices, `None` when there are none.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let mut any = false;
        for (v, p) in self.positions.iter().enumerate() {
            if self.adjacency.vertex_corner[v] != INVALID {
                lo = lo.min(*p);
                hi = hi.max(*p);
                any = true;
            }
        }
        any.then_some((lo, hi))
    }

    /// The diagonal of [`Mesh::bounds`]: the mesh's size, what a brush radius is measured by.
    pub fn extent(&self) -> Option<f32> {
        self.bounds().map(|(lo, hi)| (hi - lo).length())
    }

    /// Live faces per layer.
    pub fn faces_per_layer(&self) -> Vec<usize> {
        let mut counts = vec![0; self.layer_count()];
        for (tri, &layer) in self.faces.iter().zip(&self.face_layers) {
            if tri[0] != INVALID {
                counts[layer as usize] += 1;
            }
        }
        counts
    }
}
