//! The four edits of a remeshing pass, each over the region's edges or vertices: split long
//! edges, collapse short ones, flip toward regular valence, relax tangentially. Each checks
//! its predicates (shape, safety) before it changes the mesh.

use glam::Vec3;

use super::{
    COLLAPSE_BELOW, FLIP_FLATNESS_COSINE, MIN_AREA_SHARE, MIN_NORMAL_COSINE, RELAX_MIN_MOVE,
    Remesher, SPLIT_ABOVE, SPLIT_AT, normal,
};
use crate::mesh::{INVALID, Mesh, next, prev};

impl Remesher<'_> {
    /// Splits edges longer than 4/3·L at their midpoints, longest first: splitting the longest
    /// edge of a stretched triangle first is what makes the process converge (splitting its
    /// shorter edges first can create ever new edges toward the far corners).
    pub(super) fn split_long_edges(&mut self) {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        let limit = SPLIT_ABOVE * self.settings.target_edge;
        let mut heap: BinaryHeap<(u32, Reverse<u32>)> = BinaryHeap::new();
        let push = |heap: &mut BinaryHeap<(u32, Reverse<u32>)>, length: f32, corner: u32| {
            if length > limit {
                // Positive floats order like their bits.
                heap.push((length.to_bits(), Reverse(corner)));
            }
        };
        for c in self.region_edges() {
            push(&mut heap, self.length(c), c);
        }
        // The number of splits needed follows the area; the cap (far above it) only guards
        // against a pathological configuration.
        let mut budget = 64 * self.region.len() + 1024;
        while let Some((bits, Reverse(c))) = heap.pop() {
            if self.mesh.is_face_dead((c / 3) as usize) {
                continue;
            }
            let (a, b) = self.mesh.edge_vertices(c);
            if !(self.in_region(a) && self.in_region(b)) {
                continue;
            }
            let length = self.length(c);
            if length <= limit {
                continue;
            }
            if length.to_bits() != bits {
                // The corner names another edge now; queue it at its own length.
                push(&mut heap, length, c);
                continue;
            }
            if budget == 0 {
                break;
            }
            if self.report.splits >= self.settings.max_splits {
                self.report.growth_capped = 1;
                break;
            }
            budget -= 1;
            if !self.split_is_clear(c) {
                self.report.refused += 1;
                continue;
            }
            let o = self.mesh.adjacency().opposite[c as usize];
            let m = self.mesh.split_edge(c, SPLIT_AT);
            self.closed.adopt(m, a);
            self.closed.record(a, 0.0, if o == INVALID { 1 } else { 2 });
            self.refile_faces_around(m);
            self.grid.insert(m, self.mesh.positions()[m as usize]);
            self.add_to_region(m);
            self.mark_dirty_around(m);
            self.report.splits += 1;
            // Every edge of the faces around m may have changed: the halves, the new edges at
            // m, and the far edges of its faces.
            let corners: Vec<u32> = self.mesh.adjacency().corners_around(m).collect();
            for k in corners {
                for e in [k, next(k), prev(k)] {
                    push(&mut heap, self.length(e), e);
                }
            }
        }
    }

    pub(super) fn collapse_short_edges(&mut self) {
        let short = COLLAPSE_BELOW * self.settings.target_edge;
        let long = self.collapse_limit * self.settings.target_edge;
        for c in self.region_edges() {
            if self.mesh.is_face_dead((c / 3) as usize) || self.length(c) >= short {
                continue;
            }
            let (a, b) = self.mesh.edge_vertices(c);
            if !(self.in_region(a) && self.in_region(b)) {
                continue;
            }
            let pair = (a.min(b), a.max(b));
            if self.refused_collapses.contains(&pair) {
                continue;
            }
            // Meet in the middle; where that comes too close to another surface, stay at
            // either end (a shorter move). A boundary vertex stays where it is when only one end
            // is on the boundary.
            let o = self.mesh.adjacency().opposite[c as usize];
            let positions = self.mesh.positions();
            let middle = 0.5 * (positions[a as usize] + positions[b as usize]);
            // (Meeting in the middle from the other side would test the same faces again.)
            // Each side's link condition is asked once: nothing changes until a collapse.
            let ok_c = self.mesh.is_collapse_ok(c);
            let mut ok_o = None;
            let first = if ok_c { c } else { o };
            let choices = [
                (first, a, b, Some(middle)),
                (c, a, b, None),
                (o, b, a, None),
            ];
            let mut done = false;
            let mut refused = false;
            for (corner, keep, remove, to) in choices {
                if corner == INVALID || done {
                    continue;
                }
                let ok = match corner == c {
                    true => ok_c,
                    false => *ok_o.get_or_insert_with(|| self.mesh.is_collapse_ok(o)),
                };
                if !ok {
                    continue;
                }
                let (keep, remove) = if corner == c { (keep, remove) } else { (b, a) };
                let boundary_keep = self.mesh.is_boundary_vertex(keep);
                let boundary_remove = self.mesh.is_boundary_vertex(remove);
                let at_keep = self.mesh.positions()[keep as usize];
                let target = match to {
                    _ if boundary_keep && !boundary_remove => at_keep,
                    Some(middle) => middle,
                    None => at_keep,
                };
                if to.is_none() && target == middle {
                    continue;
                }
                if !self.collapse_shape_ok(keep, remove, target, long) {
                    continue;
                }
                let (before, after) = self.collapse_faces(keep, remove, target);
                let now = self.mesh.positions();
                let lost = [now[keep as usize], now[remove as usize]];
                let Some(volume) = self.shape_kept(keep, (&before, &after), (&lost, target)) else {
                    self.report.shape_refused += 1;
                    continue;
                };
                if !self.move_is_safe(keep, target, Some(remove)) {
                    refused = true;
                    continue;
                }
                self.grid.remove(remove);
                let survivor = self.mesh.collapse_edge(corner, target);
                let removed = before.len() - after.len();
                self.closed.record(survivor, volume, -(removed as isize));
                self.grid.move_to(survivor, target);
                self.refile_faces_around(survivor);
                self.mark_dirty_around(survivor);
                self.report.collapses += 1;
                done = true;
            }
            if refused && !done {
                self.report.refused += 1;
                self.refused_collapses.insert(pair);
            }
        }
    }

    /// New edges at the survivor stay below the split limit, and no face around it flips or
    /// degenerates.
    fn collapse_shape_ok(&self, keep: u32, remove: u32, target: Vec3, long: f32) -> bool {
        let positions = self.mesh.positions();
        let min_area = MIN_AREA_SHARE * self.settings.target_edge * self.settings.target_edge;
        for v in [keep, remove] {
            for u in self.mesh.neighbours(v) {
                if u != keep && u != remove && positions[u as usize].distance(target) > long {
                    return false;
                }
            }
            for f in self.mesh.faces_around(v) {
                let tri = self.mesh.faces()[f as usize];
                if tri.contains(&keep) && tri.contains(&remove) {
                    continue;
                }
                let old = tri.map(|w| positions[w as usize]);
                let new = tri.map(|w| {
                    if w == keep || w == remove {
                        target
                    } else {
                        positions[w as usize]
                    }
                });
                let (n_old, n_new) = (normal(old), normal(new));
                if n_new.length() * 0.5 < min_area
                    || n_old.normalize_or_zero().dot(n_new.normalize_or_zero()) < MIN_NORMAL_COSINE
                {
                    return false;
                }
            }
        }
        true
    }

    pub(super) fn flip_toward_regular_valence(&mut self) {
        for c in self.region_edges() {
            if self.mesh.is_face_dead((c / 3) as usize) {
                continue;
            }
            let (a, b) = self.mesh.edge_vertices(c);
            if !(self.is_dirty(a) || self.is_dirty(b)) || !self.mesh.is_flip_ok(c) {
                continue;
            }
            let o = self.mesh.adjacency().opposite[c as usize];
            let (x, y) = (self.mesh.corner_vertex(c), self.mesh.corner_vertex(o));
            let ideal = |m: &Mesh, v: u32| if m.is_boundary_vertex(v) { 4 } else { 6 };
            let deviation = |va: usize, vb: usize, vx: usize, vy: usize| {
                let d = |v: usize, t: i64| (v as i64 - t).abs();
                d(va, ideal(self.mesh, a))
                    + d(vb, ideal(self.mesh, b))
                    + d(vx, ideal(self.mesh, x))
                    + d(vy, ideal(self.mesh, y))
            };
            let (va, vb, vx, vy) = (
                self.mesh.valence(a),
                self.mesh.valence(b),
                self.mesh.valence(x),
                self.mesh.valence(y),
            );
            if deviation(va - 1, vb - 1, vx + 1, vy + 1) >= deviation(va, vb, vx, vy) {
                continue;
            }
            if !self.flip_shape_ok(c, o) {
                continue;
            }
            let p = self.mesh.positions();
            let [pa, pb, px, py] = [a, b, x, y].map(|v| p[v as usize]);
            // Faces (x, a, b) and (y, b, a) become (x, a, y) and (y, b, x); the old edge's
            // midpoint is what the flip takes away from the surface.
            let (before, after) = ([[px, pa, pb], [py, pb, pa]], [[px, pa, py], [py, pb, px]]);
            let middle = 0.5 * (px + py);
            let lost = [0.5 * (pa + pb)];
            let Some(volume) = self.shape_kept(a, (&before, &after), (&lost, middle)) else {
                self.report.shape_refused += 1;
                continue;
            };
            let new_faces = [([x, a, y], after[0]), ([y, b, x], after[1])];
            if !self.flip_is_clear(&new_faces, [c / 3, o / 3], &before) {
                self.report.refused += 1;
                continue;
            }
            self.closed.record(a, volume, 0);
            self.mesh.flip_edge(c);
            self.surface.faces_changed(self.mesh, [c / 3, o / 3]);
            for w in [a, b, x, y] {
                self.mark_dirty(w);
            }
            self.report.flips += 1;
        }
    }

    /// The two faces are nearly coplanar, the new ones keep their orientation, and the new
    /// edge is no longer than the old one nor past the split limit (a flip must not undo
    /// the splits).
    fn flip_shape_ok(&self, c: u32, o: u32) -> bool {
        let p = self.mesh.positions();
        let (a, b) = self.mesh.edge_vertices(c);
        let (x, y) = (self.mesh.corner_vertex(c), self.mesh.corner_vertex(o));
        let [pa, pb, px, py] = [a, b, x, y].map(|v| p[v as usize]);
        let new_length = px.distance(py);
        if new_length > SPLIT_ABOVE * self.settings.target_edge
            || new_length > pa.distance(pb) * 1.25
        {
            return false;
        }
        let (n1, n2) = (
            normal([px, pa, pb]).normalize_or_zero(),
            normal([py, pb, pa]).normalize_or_zero(),
        );
        if n1.dot(n2) < FLIP_FLATNESS_COSINE {
            return false;
        }
        let (m1, m2) = (normal([px, pa, py]), normal([py, pb, px]));
        let min_area = 2.0 * MIN_AREA_SHARE * self.settings.target_edge * self.settings.target_edge;
        m1.length() > min_area
            && m2.length() > min_area
            && m1.normalize_or_zero().dot(n1) > MIN_NORMAL_COSINE
            && m2.normalize_or_zero().dot(n1) > MIN_NORMAL_COSINE
    }

    /// Tangential relaxation toward the centroid of the one-ring, projected back onto the
    /// surface as it was, for interior region vertices; boundaries stay in place.
    pub(super) fn relax(&mut self) {
        // One set for every round, emptied in O(1), rather than a vector over the whole mesh
        // made anew each round.
        let mut movable = std::mem::take(&mut self.sets.movable);
        movable.start(self.mesh.vertex_count());
        let mut live: Vec<u32> = Vec::new();
        for &v in &self.dirty_list {
            if !self.mesh.is_vertex_live(v) {
                continue;
            }
            for u in std::iter::once(v).chain(self.mesh.neighbours(v)) {
                if self.in_region(u) && movable.insert(u as usize) {
                    live.push(u);
                }
            }
        }
        self.sets.movable = movable;
        let proposals: Vec<(u32, Vec3)> = live
            .iter()
            .filter(|&&v| !self.mesh.is_boundary_vertex(v))
            .filter_map(|&v| {
                let p = self.mesh.positions()[v as usize];
                let ring = self.mesh.neighbours(v);
                if ring.is_empty() {
                    return None;
                }
                let centroid = ring
                    .iter()
                    .map(|&u| self.mesh.positions()[u as usize])
                    .sum::<Vec3>()
                    / ring.len() as f32;
                let n = self.mesh.normals()[v as usize];
                let tangential = (centroid - p) - n * n.dot(centroid - p);
                // Projection back onto the surface barely changes a move along it: one this
                // short would not be worth its checks after it either (most vertices of an
                // even mesh, and the projection is most of a whole-mesh pass). Left out of
                // the remeshing after a stroke, whose results it would shift by an ulp here
                // and there, and whose regions are small.
                let least = RELAX_MIN_MOVE * self.settings.target_edge;
                if self.whole && tangential.length_squared() < (0.9 * least) * (0.9 * least) {
                    return None;
                }
                let moved = p + tangential;
                let layer = self.mesh.vertex_layers()[v as usize];
                let projected = self.surface.project(moved, layer).unwrap_or(moved);
                (projected.distance(p) > RELAX_MIN_MOVE * self.settings.target_edge)
                    .then_some((v, projected))
            })
            .collect();
        for (v, target) in proposals {
            if !self.relax_shape_ok(v, target) {
                continue;
            }
            let (before, after) = self.moved_faces(v, target);
            let lost = [self.mesh.positions()[v as usize]];
            let Some(volume) = self.shape_kept(v, (&before, &after), (&lost, target)) else {
                self.report.shape_refused += 1;
                continue;
            };
            if !self.move_is_safe(v, target, None) {
                self.report.refused += 1;
                continue;
            }
            self.closed.record(v, volume, 0);
            self.mesh.positions_mut()[v as usize] = target;
            self.grid.move_to(v, target);
            self.refile_faces_around(v);
            self.report.relaxed += 1;
        }
    }

    /// Moving `v` to `target` flips no face around it.
    fn relax_shape_ok(&self, v: u32, target: Vec3) -> bool {
        let p = self.mesh.positions();
        self.mesh.faces_around(v).all(|f| {
            let tri = self.mesh.faces()[f as usize];
            let old = tri.map(|w| p[w as usize]);
            let new = tri.map(|w| if w == v { target } else { p[w as usize] });
            normal(old)
                .normalize_or_zero()
                .dot(normal(new).normalize_or_zero())
                > MIN_NORMAL_COSINE
        })
    }
}
