//! Ray picking for the brush under the cursor: which face a pointer's ray meets first.
//!
//! Faces are sorted along a Morton curve of their centroids and cut into clusters of
//! [`CLUSTER_FACES`] neighbours, each with a bounding box. A stroke moves vertices but keeps the
//! faces, so the boxes are refitted from the vertices a sample changed ([`Picker::refit`]);
//! only a change of topology (remeshing) needs [`Picker::build`] again. A ray tests every
//! cluster's box (a few thousand slab tests at a million faces) and then the faces of the boxes
//! it enters, nearest first, until no box can hold a nearer hit.

use glam::Vec3;

pub use crate::geom::Ray;
use crate::geom::ray_triangle;
use crate::mesh::{INVALID, Mesh};

/// Faces per cluster: small enough that a ray tests few faces, large enough that the box test
/// over all clusters stays cheap.
const CLUSTER_FACES: usize = 64;

/// Where a ray met the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub point: Vec3,
    /// The face's unit normal, turned toward the ray's origin.
    pub normal: Vec3,
    pub face: u32,
    /// Along the ray.
    pub distance: f32,
}

#[derive(Debug, Clone, Copy)]
struct Cluster {
    lo: Vec3,
    hi: Vec3,
    /// Range in `Picker::order`.
    start: u32,
    end: u32,
}

/// The clusters of one mesh's visible faces.
#[derive(Debug, Clone, Default)]
pub struct Picker {
    /// Face numbers, cluster by cluster.
    order: Vec<u32>,
    clusters: Vec<Cluster>,
    /// Per face: its cluster, or [`INVALID`] (dead, hidden or not finite).
    face_cluster: Vec<u32>,
}

impl Picker {
    /// Clusters the live faces of the layers `visible` says are shown.
    pub fn build(mesh: &Mesh, visible: &[bool]) -> Picker {
        let positions = mesh.positions();
        let pickable = |f: usize| {
            let face = mesh.faces()[f];
            face[0] != INVALID
                && !mesh.is_face_dead(f)
                && visible
                    .get(mesh.face_layers()[f] as usize)
                    .copied()
                    .unwrap_or(true)
                && face.iter().all(|&v| positions[v as usize].is_finite())
        };
        let faces: Vec<u32> = (0..mesh.face_count())
            .filter(|&f| pickable(f))
            .map(|f| f as u32)
            .collect();
        let centroids: Vec<Vec3> = faces
            .iter()
            .map(|&f| {
                let [a, b, c] = mesh.faces()[f as usize];
                (positions[a as usize] + positions[b as usize] + positions[c as usize]) / 3.0
            })
            .collect();
        let (lo, hi) = centroids.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let scale = 1023.0 / (hi - lo).max(Vec3::splat(1e-12));
        let mut keyed: Vec<(u32, u32)> = faces
            .iter()
            .zip(&centroids)
            .map(|(&f, &p)| (morton((p - lo) * scale), f))
            .collect();
        keyed.sort_unstable();
        let order: Vec<u32> = keyed.into_iter().map(|(_, f)| f).collect();
        let mut face_cluster = vec![INVALID; mesh.face_count()];
        let mut clusters = Vec::with_capacity(order.len().div_ceil(CLUSTER_FACES));
        for (c, chunk) in order.chunks(CLUSTER_FACES).enumerate() {
            let start = (c * CLUSTER_FACES) as u32;
            chunk
                .iter()
                .for_each(|&f| face_cluster[f as usize] = c as u32);
            let mut cluster = Cluster {
                lo: Vec3::ZERO,
                hi: Vec3::ZERO,
                start,
                end: start + chunk.len() as u32,
            };
            fit(&mut cluster, &order, mesh);
            clusters.push(cluster);
        }
        Picker {
            order,
            clusters,
            face_cluster,
        }
    }

    /// Refits the boxes of the clusters holding a face around one of `changed` (vertices that
    /// moved); faces must be those [`Picker::build`] saw.
    pub fn refit(&mut self, mesh: &Mesh, changed: &[u32]) {
        let mut dirty: Vec<u32> = Vec::new();
        for &v in changed {
            if (v as usize) >= mesh.vertex_count() || mesh.is_vertex_dead(v) {
                continue;
            }
            for f in mesh.faces_around(v) {
                match self.face_cluster.get(f as usize) {
                    Some(&c) if c != INVALID => dirty.push(c),
                    _ => {}
                }
            }
        }
        dirty.sort_unstable();
        dirty.dedup();
        for c in dirty {
            fit(&mut self.clusters[c as usize], &self.order, mesh);
        }
    }

    /// The nearest face `ray` meets (either side), if any.
    pub fn pick(&self, mesh: &Mesh, ray: &Ray) -> Option<Hit> {
        let inverse = ray.direction.recip();
        let mut entered: Vec<(f32, u32)> = self
            .clusters
            .iter()
            .enumerate()
            .filter_map(|(c, cluster)| {
                slab_entry(ray.origin, inverse, cluster.lo, cluster.hi).map(|t| (t, c as u32))
            })
            .collect();
        entered.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut best: Option<(f32, u32)> = None;
        for (entry, c) in entered {
            if best.is_some_and(|(t, _)| entry > t) {
                break;
            }
            let cluster = &self.clusters[c as usize];
            for &f in &self.order[cluster.start as usize..cluster.end as usize] {
                let [a, b, c] = mesh.faces()[f as usize].map(|v| mesh.positions()[v as usize]);
                if let Some(t) = ray_triangle(ray, a, b, c)
                    && best.is_none_or(|(best_t, _)| t < best_t)
                {
                    best = Some((t, f));
                }
            }
        }
        let (distance, face) = best?;
        let [a, b, c] = mesh.faces()[face as usize].map(|v| mesh.positions()[v as usize]);
        let mut normal = (b - a).cross(c - a).normalize_or_zero();
        if normal.dot(ray.direction) > 0.0 {
            normal = -normal;
        }
        Some(Hit {
            point: ray.at(distance),
            normal,
            face,
            distance,
        })
    }
}

/// The cluster's box around its faces' current corners.
fn fit(cluster: &mut Cluster, order: &[u32], mesh: &Mesh) {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for &f in &order[cluster.start as usize..cluster.end as usize] {
        for v in mesh.faces()[f as usize] {
            let p = mesh.positions()[v as usize];
            if p.is_finite() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    cluster.lo = lo;
    cluster.hi = hi;
}

/// Where a ray enters the box (0 when it starts inside), or `None` when it misses it.
fn slab_entry(origin: Vec3, inverse: Vec3, lo: Vec3, hi: Vec3) -> Option<f32> {
    let (mut near, mut far) = (0.0f32, f32::INFINITY);
    for axis in 0..3 {
        let t0 = (lo[axis] - origin[axis]) * inverse[axis];
        let t1 = (hi[axis] - origin[axis]) * inverse[axis];
        // A ray parallel to this slab's planes (an infinite inverse) lying on one of them
        // gives 0 × ∞ = NaN: it is inside the slab along this axis, which constrains nothing.
        if t0.is_nan() || t1.is_nan() {
            continue;
        }
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1));
    }
    (near <= far).then_some(near)
}

/// Interleaves the bits of three 10-bit coordinates.
fn morton(p: Vec3) -> u32 {
    fn spread(x: f32) -> u32 {
        let mut v = (x.clamp(0.0, 1023.0) as u32) & 0x3ff;
        v = (v | (v << 16)) & 0x030000ff;
        v = (v | (v << 8)) & 0x0300f00f;
        v = (v | (v << 4)) & 0x030c30c3;
        (v | (v << 2)) & 0x09249249
    }
    spread(p.x) | (spread(p.y) << 1) | (spread(p.z) << 2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{SceneKind, SceneSpec, generate};

    fn plaster() -> Mesh {
        generate(&SceneSpec {
            kind: SceneKind::Plaster,
            triangles: 2_000,
            seed: 3,
        })
        .unwrap()
    }

    /// Every face, brute force: the oracle the clusters must agree with.
    fn brute_force(mesh: &Mesh, ray: &Ray) -> Option<(f32, u32)> {
        (0..mesh.face_count())
            .filter(|&f| !mesh.is_face_dead(f))
            .filter_map(|f| {
                let [a, b, c] = mesh.faces()[f].map(|v| mesh.positions()[v as usize]);
                ray_triangle(ray, a, b, c).map(|t| (t, f as u32))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    #[test]
    fn picks_the_nearest_face_like_brute_force_after_vertices_move() {
        let mut mesh = plaster();
        let visible = vec![true; mesh.layer_count()];
        let mut picker = Picker::build(&mesh, &visible);
        // Lift a patch, as a stroke would, and refit.
        let moved: Vec<u32> = (0..mesh.vertex_count() as u32)
            .filter(|&v| {
                (mesh.positions()[v as usize].truncate() - glam::Vec2::splat(0.5)).length() < 0.1
            })
            .collect();
        assert!(!moved.is_empty());
        for &v in &moved {
            mesh.positions_mut()[v as usize].z += 0.2;
        }
        picker.refit(&mesh, &moved);
        let mut hits = 0;
        for i in 0..400 {
            let x = (i % 20) as f32 / 19.0;
            let y = (i / 20) as f32 / 19.0;
            let origin = Vec3::new(x, y, 2.0);
            let ray = Ray {
                origin,
                direction: (Vec3::new(0.5, 0.5, 0.0) - origin).normalize() * 0.2
                    + Vec3::new(0.0, 0.0, -1.0),
            };
            let ray = Ray {
                direction: ray.direction.normalize(),
                ..ray
            };
            let expected = brute_force(&mesh, &ray);
            let got = picker.pick(&mesh, &ray).map(|h| (h.distance, h.face));
            assert_eq!(got, expected, "ray {i}");
            hits += got.is_some() as usize;
        }
        assert!(hits > 100, "only {hits} of 400 rays met the sheet");
    }

    #[test]
    fn a_ray_along_a_box_face_still_enters_the_box() {
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        // Straight down, on the plane x = 0 of the box.
        let origin = Vec3::new(0.0, 0.5, 2.0);
        let entry = slab_entry(origin, Vec3::NEG_Z.recip(), lo, hi);
        assert_eq!(entry, Some(1.0));
        let beside = slab_entry(Vec3::new(-0.1, 0.5, 2.0), Vec3::NEG_Z.recip(), lo, hi);
        assert_eq!(beside, None);
    }

    #[test]
    fn hidden_layers_are_not_picked() {
        let mesh = plaster();
        assert!(mesh.layer_count() >= 2);
        let mut visible = vec![true; mesh.layer_count()];
        visible[mesh.layer_count() - 1] = false;
        let picker = Picker::build(&mesh, &visible);
        let ray = Ray {
            origin: Vec3::new(0.5, 0.5, 3.0),
            direction: Vec3::NEG_Z,
        };
        let hit = picker
            .pick(&mesh, &ray)
            .expect("a lower layer is under the ray");
        assert!(visible[mesh.face_layers()[hit.face as usize] as usize]);
        assert!(hit.normal.z > 0.0, "the normal faces the eye");
    }
}
