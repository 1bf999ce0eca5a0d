//! The surface as it was before remeshing: where relaxed vertices are projected back to, and the
//! index of every face near the region that collision checks read (at current positions).

use glam::{IVec3, Vec3};
use rustc_hash::FxHashMap;
use std::collections::hash_map::Entry;

use super::RemeshSettings;
use crate::collide::{LocalFaceGrid, Stamps};
use crate::geom::{Aabb, closest_point_on_triangle};
use crate::grid::SpatialHash;
use crate::mesh::{INVALID, Mesh};

/// Share of the search radius and of the point's size by which a triangle's box must lie
/// beyond the best distance so far to be skipped: `f32` closest points are off by a few ulps
/// of the coordinates, far less.
const PRUNE_SLACK: f32 = 1e-4;

pub struct ReferenceSurface {
    /// Faces near the region when remeshing began, their triangles then, and their layers,
    /// filed in `grid` under their own boxes.
    faces: Vec<u32>,
    triangles: Vec<[Vec3; 3]>,
    boxes: Vec<Aabb>,
    layers: Vec<u32>,
    grid: LocalFaceGrid,
    /// Local index of each captured face, and which of them an edit changed since: those are
    /// looked up in `moved` instead.
    local: FxHashMap<u32, u32>,
    captured_changed: Stamps,
    /// The faces edits made or changed (mesh indices), numbered in the order they first
    /// changed, and each one's number and the cells it was last filed in.
    changed: Vec<u32>,
    filed: FxHashMap<u32, (u32, (IVec3, IVec3))>,
    /// Changed faces by number, filed by `grid`'s cells under their boxes when they changed;
    /// an entry whose face has moved on since is filtered by its box now. Everything here is
    /// as large as the pass's work, never as the mesh.
    moved: FxHashMap<usize, Vec<u32>>,
    search: f32,
    seen: std::cell::RefCell<Stamps>,
    /// The local face that last answered [`Self::is_near`].
    last_near: std::cell::Cell<u32>,
}

impl ReferenceSurface {
    pub fn capture(
        mesh: &Mesh,
        grid: &SpatialHash,
        region: &[u32],
        settings: &RemeshSettings,
    ) -> Self {
        let l = settings.target_edge;
        let bounds = region.iter().fold(Aabb::EMPTY, |b, &v| {
            b.including(mesh.positions()[v as usize])
        });
        let reach = settings.collision_distance + 3.0 * l;
        let area = bounds.expanded(reach);
        let mut vertices = Vec::new();
        if !bounds.is_empty() {
            grid.for_each_in_box(area.min, area.max, |v| vertices.push(v));
        }
        let mut faces: Vec<u32> = vertices
            .iter()
            .flat_map(|&v| mesh.faces_around(v))
            .collect();
        faces.sort_unstable();
        faces.dedup();
        let triangles: Vec<[Vec3; 3]> = faces
            .iter()
            .map(|&f| mesh.face_positions(f as usize))
            .collect();
        let layers = faces
            .iter()
            .map(|&f| mesh.face_layers()[f as usize])
            .collect();
        let boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::of_points(t)).collect();
        let mut local_grid = LocalFaceGrid::default();
        if !faces.is_empty() {
            local_grid.build(&boxes, area.expanded(l), 1.5 * l);
        }
        let local = faces
            .iter()
            .enumerate()
            .map(|(i, &f)| (f, i as u32))
            .collect();
        let mut captured_changed = Stamps::default();
        captured_changed.start(faces.len());
        ReferenceSurface {
            seen: std::cell::RefCell::new(Stamps::default()),
            last_near: std::cell::Cell::new(u32::MAX),
            faces,
            triangles,
            boxes,
            layers,
            grid: local_grid,
            local,
            captured_changed,
            changed: Vec::new(),
            filed: FxHashMap::default(),
            moved: FxHashMap::default(),
            search: l,
        }
    }

    /// An edit made or changed `faces` (their vertices or where those are): they are found
    /// where they are now from here on.
    pub fn faces_changed(&mut self, mesh: &Mesh, faces: impl IntoIterator<Item = u32>) {
        for face in faces {
            if let Some(&i) = self.local.get(&face) {
                self.captured_changed.insert(i as usize);
            }
            let ids = mesh.faces()[face as usize];
            if ids[0] == INVALID {
                continue;
            }
            let now = Aabb::of_points(&ids.map(|w| mesh.positions()[w as usize]));
            let span = self.grid.cell_span(&now);
            let (number, before) = match self.filed.entry(face) {
                Entry::Occupied(mut filed) => {
                    let (number, before) = *filed.get();
                    filed.insert((number, span));
                    (number, Some(before))
                }
                Entry::Vacant(filed) => {
                    let number = self.changed.len() as u32;
                    filed.insert((number, span));
                    self.changed.push(face);
                    (number, None)
                }
            };
            // Most edits move a face less than a cell: it is filed once per cell it reaches.
            if before == Some(span) {
                continue;
            }
            let filed_before =
                |at: IVec3| before.is_some_and(|(lo, hi)| at.cmpge(lo).all() && at.cmple(hi).all());
            let moved = &mut self.moved;
            self.grid.for_each_cell(span, |cell, at| {
                if !filed_before(at) {
                    moved.entry(cell).or_default().push(number);
                }
            });
        }
    }

    /// Calls `f` with every face (by mesh index) that may overlap `query` where it is now,
    /// once each: the captured faces no edit changed whose boxes overlap it, and the changed
    /// ones filed in the cells it covers.
    pub fn for_each_near(&self, query: &Aabb, mut f: impl FnMut(u32)) {
        let mut seen = self.seen.borrow_mut();
        seen.start(self.faces.len());
        self.grid.for_each_candidate(query, |local| {
            let i = local as usize;
            if self.captured_changed.contains(i) || !seen.insert(i) {
                return;
            }
            if self.boxes[i].overlaps(query) {
                f(self.faces[i]);
            }
        });
        if self.changed.is_empty() {
            return;
        }
        seen.start(self.changed.len());
        self.grid
            .for_each_cell(self.grid.cell_span(query), |cell, _| {
                for &number in self.moved.get(&cell).map_or(&[][..], Vec::as_slice) {
                    if seen.insert(number as usize) {
                        f(self.changed[number as usize]);
                    }
                }
            });
    }

    /// Whether the original surface of `layer` comes within `distance` (at most an edge
    /// length) of `p`.
    pub fn is_near(&self, p: Vec3, layer: u32, distance: f32) -> bool {
        let d2 = distance * distance;
        let near = |local: u32| {
            let i = local as usize;
            if self.layers[i] != layer {
                return false;
            }
            // Most candidates are filed in cells the query only grazes: their boxes reject them.
            let Aabb { min: lo, max: hi } = self.boxes[i];
            if (p.cmplt(lo - distance) | p.cmpgt(hi + distance)).any() {
                return false;
            }
            let [a, b, c] = self.triangles[i];
            closest_point_on_triangle(p, a, b, c).distance_squared(p) <= d2
        };
        // An edit asks about a few points close together: the face that answered the last
        // question usually answers this one, without walking the grid.
        let hint = self.last_near.get();
        if (hint as usize) < self.faces.len() && near(hint) {
            return true;
        }
        let query = Aabb { min: p, max: p }.expanded(distance);
        self.grid.any_candidate(&query, |local| {
            let found = near(local);
            if found {
                self.last_near.set(local);
            }
            found
        })
    }

    /// The closest point of the original surface of `layer` to `p`, within an edge length.
    pub fn project(&self, p: Vec3, layer: u32) -> Option<Vec3> {
        let query = Aabb { min: p, max: p }.expanded(self.search);
        // The nearest, and of equally near ones the first captured: the answer does not
        // depend on the order the grid lists faces in.
        let mut best: Option<(f32, usize, Vec3)> = None;
        let slack = PRUNE_SLACK * (self.search + p.abs().max_element());
        let mut seen = self.seen.borrow_mut();
        seen.start(self.faces.len());
        self.grid.for_each_candidate(&query, |local| {
            let i = local as usize;
            if self.layers[i] != layer || !seen.insert(i) {
                return;
            }
            let [a, b, c] = self.triangles[i];
            // A triangle whose box is farther than the best so far cannot beat it; the slack
            // keeps the skip clear of the closest point's rounding, so the answer is the same.
            if let Some((best_d, _, _)) = best {
                let gap = self.boxes[i].distance_squared_to(p).sqrt();
                if gap > best_d.sqrt() + slack {
                    return;
                }
            }
            let q = closest_point_on_triangle(p, a, b, c);
            let d = q.distance_squared(p);
            if best.is_none_or(|(bd, bi, _)| d < bd || (d == bd && i < bi)) {
                best = Some((d, i, q));
            }
        });
        best.filter(|(d, _, _)| *d <= self.search * self.search)
            .map(|(_, _, q)| q)
    }
}
