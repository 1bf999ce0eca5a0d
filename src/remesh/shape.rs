//! Keeping the shape while remeshing (issue 22): an edit is refused when it would move the
//! surface more than [`SHAPE_TOLERANCE`]·L from the surface before remeshing (both ways: the
//! new faces must lie near the old surface, and the points the edit removes or moves must lie
//! near the new faces), when it would change a closed component's volume by more than
//! [`VOLUME_TOLERANCE`] of it over the pass, or when it would take a closed component below
//! [`MIN_CLOSED_FACES`] faces. Without these, relaxation slides the corners of a coarse cube
//! onto its faces and collapses then fold it into a sliver tetrahedron.

use glam::Vec3;
use rustc_hash::{FxHashMap, FxHashSet};

use super::Remesher;
use crate::geom::closest_point_on_triangle;
use crate::mesh::Mesh;

/// How far (× L) an edit may move the surface from where it was when remeshing began. Above
/// the chord error of a smooth surface sampled at L (L²/8R: 0.06·L on a sphere of radius 2·L),
/// so smooth surfaces remesh freely; measured on a jittered plaster scene, 0.2·L leaves the
/// remesher's edge spread and angles as they were without the bound, where 0.1·L worsens them.
/// Corners and creases of coarse meshes stay: their vertices are farther than that from any
/// face that would replace them.
pub const SHAPE_TOLERANCE: f32 = 0.2;
/// The largest share of a closed component's volume one remeshing pass may change. Coarsening
/// a sphere of radius 0.5 from L = 0.06 to 0.1 changes it by 1.75 % (the inscribed polyhedron
/// shrinks), which must pass; a cube losing a corner loses 17 %.
pub const VOLUME_TOLERANCE: f64 = 0.02;
/// A closed component never drops below this many faces by remeshing (an octahedron's; a
/// tetrahedron's 4 is what a collapsed cube became). `slayer check` reports fewer.
pub const MIN_CLOSED_FACES: usize = 8;
/// Faces a pass may visit per region vertex to find the closed components it touches. A
/// component larger than that is far larger than the region, and the shape tolerance already
/// bounds the pass's volume change to a small share of it.
const TRACKING_FACES_PER_REGION_VERTEX: usize = 16;
const TRACKING_FACES_MIN: usize = 4096;

/// The closed components a pass works on, with their volumes and what the pass changed.
#[derive(Default)]
pub(super) struct ClosedParts {
    of_vertex: FxHashMap<u32, u32>,
    parts: Vec<Part>,
}

#[derive(Clone, Copy)]
struct Part {
    faces: usize,
    change: f64,
    /// How far `change` may go either way: [`VOLUME_TOLERANCE`] of the volume, or a share's
    /// part of what its pass had left ([`ClosedParts::share`]).
    limit: f64,
    /// The fewest faces the part may be left with, and the count it started from here.
    least_faces: usize,
    start_faces: usize,
}

impl ClosedParts {
    /// Finds the closed components of the `region` vertices, within a budget of faces visited.
    pub(super) fn find(mesh: &Mesh, region: &[u32]) -> Self {
        let mut budget = TRACKING_FACES_MIN + TRACKING_FACES_PER_REGION_VERTEX * region.len();
        let mut parts = ClosedParts::default();
        let mut seen: FxHashSet<u32> = FxHashSet::default();
        for &start in region {
            if budget == 0 {
                break;
            }
            if seen.contains(&start) || mesh.faces_around(start).next().is_none() {
                continue;
            }
            let found = component_faces(mesh, start, &mut seen, &mut budget);
            if let Some((vertices, faces)) = found {
                let id = parts.parts.len() as u32;
                let volume = signed_volume(
                    faces.iter().map(|&f| mesh.face_positions(f as usize)),
                    mesh.positions()[start as usize],
                );
                parts.parts.push(Part {
                    faces: faces.len(),
                    change: 0.0,
                    limit: VOLUME_TOLERANCE * volume.abs(),
                    least_faces: MIN_CLOSED_FACES,
                    start_faces: faces.len(),
                });
                parts
                    .of_vertex
                    .extend(vertices.into_iter().map(|v| (v, id)));
            }
        }
        parts
    }

    /// Whether an edit at `v` that changes the volume by `delta` and removes `faces_removed`
    /// faces keeps its component (if closed and tracked) within the bounds.
    pub(super) fn allows(&self, v: u32, delta: f64, faces_removed: usize) -> bool {
        let Some(&id) = self.of_vertex.get(&v) else {
            return true;
        };
        let part = &self.parts[id as usize];
        part.faces >= part.least_faces + faces_removed && (part.change + delta).abs() <= part.limit
    }

    /// Books an edit [`allows`](Self::allows) let through.
    pub(super) fn record(&mut self, v: u32, delta: f64, faces_added: isize) {
        if let Some(&id) = self.of_vertex.get(&v) {
            let part = &mut self.parts[id as usize];
            part.change += delta;
            part.faces = part.faces.saturating_add_signed(faces_added);
        }
    }

    /// The bounds left to this pass split `ways` ways, for one of that many copies of parts of
    /// the mesh remeshed at once (`slabs`), its vertices renumbered: the copy's vertex `i` is
    /// the mesh's `sources[i]`. Each share may change a part's volume by its `ways`-th of what
    /// the pass may still change, and remove its `ways`-th of the faces above the least, so
    /// all the shares together keep the pass within the bounds.
    pub(super) fn share(&self, sources: &[u32], ways: usize) -> ClosedParts {
        let of_vertex = sources
            .iter()
            .enumerate()
            .filter_map(|(i, v)| self.of_vertex.get(v).map(|&id| (i as u32, id)))
            .collect();
        let parts = self
            .parts
            .iter()
            .map(|part| Part {
                change: 0.0,
                limit: (part.limit - part.change.abs()).max(0.0) / ways as f64,
                least_faces: part.faces - part.faces.saturating_sub(part.least_faces) / ways,
                start_faces: part.faces,
                ..*part
            })
            .collect();
        ClosedParts { of_vertex, parts }
    }

    /// Books what a [`share`](Self::share) changed, its vertices renumbered back: the copy's
    /// vertex `i` is now the mesh's `vertex_map[i]` (`INVALID`: removed).
    pub(super) fn absorb(&mut self, share: &ClosedParts, vertex_map: &[u32]) {
        for (whole, part) in self.parts.iter_mut().zip(&share.parts) {
            whole.change += part.change;
            whole.faces = (whole.faces + part.faces).saturating_sub(part.start_faces);
        }
        for (&i, &id) in &share.of_vertex {
            match vertex_map.get(i as usize) {
                Some(&v) if v != crate::mesh::INVALID => {
                    self.of_vertex.insert(v, id);
                }
                _ => {}
            }
        }
    }

    /// A vertex split into `from`'s edge joins its component.
    pub(super) fn adopt(&mut self, new: u32, from: u32) {
        if let Some(&id) = self.of_vertex.get(&from) {
            self.of_vertex.insert(new, id);
        }
    }
}

/// The vertices and faces of `start`'s component when it is closed and fits in `budget`
/// faces (spent either way); `None` for an open or larger one. Visited vertices join `seen`.
fn component_faces(
    mesh: &Mesh,
    start: u32,
    seen: &mut FxHashSet<u32>,
    budget: &mut usize,
) -> Option<(Vec<u32>, Vec<u32>)> {
    let mut vertices = vec![start];
    let mut faces = Vec::new();
    let mut faces_seen: FxHashSet<u32> = FxHashSet::default();
    seen.insert(start);
    let mut next = 0;
    while next < vertices.len() {
        let v = vertices[next];
        next += 1;
        if mesh.is_boundary_vertex(v) {
            return None;
        }
        for f in mesh.faces_around(v) {
            if !faces_seen.insert(f) {
                continue;
            }
            if *budget == 0 {
                return None;
            }
            *budget -= 1;
            faces.push(f);
            for w in mesh.faces()[f as usize] {
                if seen.insert(w) {
                    vertices.push(w);
                }
            }
        }
    }
    Some((vertices, faces))
}

/// The signed volume enclosed by `triangles` with `origin` (a point near them, for precision):
/// of a closed surface, its volume; of an edit's faces before and after, the difference is the
/// volume the edit changes (they share their outline).
pub(super) fn signed_volume(triangles: impl Iterator<Item = [Vec3; 3]>, origin: Vec3) -> f64 {
    let o = origin.as_dvec3();
    triangles
        .map(|t| {
            let [a, b, c] = t.map(|p| p.as_dvec3() - o);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Where a new face is sampled against the old surface: its centroid and the midpoints of the
/// edges at `at` (its far edge is an old edge, on the old surface already).
fn samples(t: &[Vec3; 3], at: Vec3) -> impl Iterator<Item = Vec3> + '_ {
    let centroid = (t[0] + t[1] + t[2]) / 3.0;
    std::iter::once(centroid).chain(
        t.iter()
            .filter(move |&&p| p != at)
            .map(move |&p| 0.5 * (p + at)),
    )
}

impl Remesher<'_> {
    /// The faces around `keep` and `remove` now, and those a collapse of the edge between them
    /// to `target` leaves (the two on the edge gone).
    pub(super) fn collapse_faces(
        &self,
        keep: u32,
        remove: u32,
        target: Vec3,
    ) -> (Vec<[Vec3; 3]>, Vec<[Vec3; 3]>) {
        let p = self.mesh.positions();
        let mut faces: Vec<u32> = self.mesh.faces_around(keep).collect();
        faces.extend(self.mesh.faces_around(remove));
        faces.sort_unstable();
        faces.dedup();
        let (mut before, mut after) = (Vec::new(), Vec::new());
        for f in faces {
            let tri = self.mesh.faces()[f as usize];
            before.push(tri.map(|w| p[w as usize]));
            if !(tri.contains(&keep) && tri.contains(&remove)) {
                after.push(tri.map(|w| {
                    if w == keep || w == remove {
                        target
                    } else {
                        p[w as usize]
                    }
                }));
            }
        }
        (before, after)
    }

    /// The faces around `v` now, and with `v` at `target`.
    pub(super) fn moved_faces(&self, v: u32, target: Vec3) -> (Vec<[Vec3; 3]>, Vec<[Vec3; 3]>) {
        let p = self.mesh.positions();
        self.mesh
            .faces_around(v)
            .map(|f| {
                let tri = self.mesh.faces()[f as usize];
                (
                    tri.map(|w| p[w as usize]),
                    tri.map(|w| if w == v { target } else { p[w as usize] }),
                )
            })
            .unzip()
    }

    /// Whether replacing `before` by `after` (faces of `v`'s layer, at positions) keeps the
    /// surface within the tolerance of where it was: every `lost` point (a vertex removed or
    /// moved away, an edge flipped away) near the new faces, the new faces (sampled about
    /// `at`, the point the edit moved) near the surface before remeshing, and a closed
    /// component's volume and face count within bounds. Returns the volume change when kept.
    pub(super) fn shape_kept(
        &self,
        v: u32,
        (before, after): (&[[Vec3; 3]], &[[Vec3; 3]]),
        (lost, at): (&[Vec3], Vec3),
    ) -> Option<f64> {
        let tolerance = SHAPE_TOLERANCE * self.settings.target_edge;
        let near_new = |p: Vec3| {
            after.iter().any(|t| {
                closest_point_on_triangle(p, t[0], t[1], t[2]).distance_squared(p)
                    <= tolerance * tolerance
            })
        };
        if !lost.iter().all(|&p| near_new(p)) {
            return None;
        }
        let delta =
            signed_volume(after.iter().copied(), at) - signed_volume(before.iter().copied(), at);
        let removed = before.len().saturating_sub(after.len());
        if !self.closed.allows(v, delta, removed) {
            return None;
        }
        let layer = self.mesh.vertex_layers()[v as usize];
        // Faces around `at` share their edges' midpoints: each point is asked once.
        // (A fan too large for the list asks its last points again.)
        let mut asked = [Vec3::NAN; 48];
        let mut count = 0;
        let mut near_old = |p: Vec3| {
            if asked[..count].contains(&p) {
                return true;
            }
            if let Some(slot) = asked.get_mut(count) {
                *slot = p;
                count += 1;
            }
            self.surface.is_near(p, layer, tolerance)
        };
        after
            .iter()
            .all(|t| samples(t, at).all(&mut near_old))
            .then_some(delta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes;

    #[test]
    fn a_closed_shape_encloses_its_volume() {
        let tetra = shapes::tetrahedron();
        let faces = (0..tetra.face_count()).map(|f| tetra.face_positions(f));
        let volume = signed_volume(faces, Vec3::splat(7.0));
        let [a, b, c, d] = [0, 1, 2, 3].map(|v| tetra.positions()[v].as_dvec3());
        let expected = (b - a).dot((c - a).cross(d - a)).abs() / 6.0;
        assert!(
            (volume.abs() - expected).abs() < 1e-9,
            "{volume} vs {expected}"
        );
        let parts = ClosedParts::find(&tetra, &[0, 1, 2, 3]);
        assert_eq!(parts.parts.len(), 1);
        assert_eq!(parts.parts[0].faces, 4);
        // Already below the floor: no collapse may remove faces from it.
        assert!(!parts.allows(0, 0.0, 2));
    }
}
