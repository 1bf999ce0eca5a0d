//! The remesher's safety checks: whether an edit that moves a vertex keeps it from coming closer
//! than the collision distance to any face outside its neighbourhood, and leaves its faces
//! crossing no other layer (exactly, with `geom`'s predicates). Splitting them from the edit
//! loop (`super`) keeps each file to one concern: what to edit, and whether it is safe.

use glam::Vec3;

use super::{IdTriangle, NearFace, Remesher, SPLIT_AT};
use crate::collide::neighbourhood::{in_ring, ring_vertices};
use crate::geom::{Aabb, neighbours_overlap, point_triangle_distance, triangles_intersect};
use crate::mesh::INVALID;

impl Remesher<'_> {
    /// A vertex (with `merged`, when a collapse takes it along) may move to `target` only if no
    /// face outside its neighbourhood gets closer than the collision distance (or than it
    /// already was), and its faces at the new position cross no other layer.
    pub(super) fn move_is_safe(&mut self, v: u32, target: Vec3, merged: Option<u32>) -> bool {
        // Lists kept between edits: a pass asks this of every collapse and relaxation.
        let (mut carrying, mut moved) = std::mem::take(&mut self.move_lists);
        carrying.clear();
        moved.clear();
        for w in [Some(v), merged].into_iter().flatten() {
            carrying.extend(self.mesh.faces_around(w));
        }
        // The faces that will carry the vertex, at their new positions.
        let (positions, faces) = (self.mesh.positions(), self.mesh.faces());
        moved.extend(carrying.iter().filter_map(|&f| {
            let tri = faces[f as usize];
            if merged.is_some_and(|m| tri.contains(&m) && tri.contains(&v)) {
                return None;
            }
            let ids = tri.map(|w| if Some(w) == merged { v } else { w });
            let at = ids.map(|w| {
                if w == v {
                    target
                } else {
                    positions[w as usize]
                }
            });
            Some((ids, at))
        }));
        // The rim stays as it is unless a rim vertex moves or is merged away (asked only
        // where a zone could vouch: a stroke's remesh has none).
        let rim = |w: u32| self.mesh.is_boundary_vertex(w);
        let keeps_rim = self.zone.is_some()
            && merged.is_none_or(|m| !rim(m))
            && (!rim(v) || positions[v as usize] == target);
        let in_zone = |remesher: &mut Self| remesher.clear_in_zone(v, target, merged);
        let safe = self.unless_vouched(
            &moved,
            keeps_rim,
            (in_zone, |remesher| {
                remesher.move_checks(v, (target, merged), &carrying, &moved)
            }),
        );
        self.move_lists = (carrying, moved);
        safe
    }

    /// A move the sheet zone vouches for: safe, unless the pass keeps the zone's moves from
    /// their own layer (`Remesher::zone_keeps_own_gap`). The zone settles crossings and other
    /// layers, not how near the vertex comes to its own layer beyond its exclusion ring: a
    /// sheet pressed together brings its second ring within `d`, which the full checks refuse.
    fn clear_in_zone(&mut self, v: u32, target: Vec3, merged: Option<u32>) -> bool {
        if !self.zone_keeps_own_gap {
            return true;
        }
        let d = self.settings.collision_distance;
        let from = self.mesh.positions()[v as usize];
        let near = self.gather_near(&Aabb::of_points(&[from, target]).expanded(d));
        let clear = self.keeps_collision_distance(v, (from, target, merged), &near);
        self.near = near;
        clear
    }

    /// No face near `target` but those of `v`'s own neighbourhood (its exclusion ring in its
    /// layer, and `merged`'s when a collapse takes it along) is within the collision distance
    /// of it, unless it already was as near to `from`. `near` holds every face within that
    /// distance of `target`.
    fn keeps_collision_distance(
        &mut self,
        v: u32,
        (from, target, merged): (Vec3, Vec3, Option<u32>),
        near: &[NearFace],
    ) -> bool {
        let d = self.settings.collision_distance;
        let mut ring = std::mem::take(&mut self.scratch);
        ring_vertices(self.mesh, v, self.settings.exclusion_ring, &mut ring);
        if let Some(m) = merged {
            let mut more = Vec::new();
            ring_vertices(self.mesh, m, self.settings.exclusion_ring, &mut more);
            ring.extend(more);
            ring.sort_unstable();
            ring.dedup();
        }
        let layer = self.mesh.vertex_layers()[v as usize];
        let face_layers = self.mesh.face_layers();
        let safe = near.iter().all(|candidate| {
            // The neighbourhood skipped is the vertex's own, in its own layer; faces beyond
            // the collision distance do not matter.
            let own = face_layers[candidate.face as usize] == layer
                && candidate.ids.iter().any(|&w| in_ring(&ring, w));
            if own || !candidate.bounds.within(target, d) {
                return true;
            }
            let now = point_triangle_distance(target, candidate.at);
            !(now < d && now < point_triangle_distance(from, candidate.at))
        });
        self.scratch = ring;
        safe
    }

    /// [`Self::move_is_safe`]'s checks in full, given the faces around the moving vertices
    /// (`carrying`) and the faces they become (`moved`).
    fn move_checks(
        &mut self,
        v: u32,
        (target, merged): (Vec3, Option<u32>),
        carrying: &[u32],
        moved: &[IdTriangle],
    ) -> bool {
        let d = self.settings.collision_distance;
        let from = self.mesh.positions()[v as usize];
        let layer = self.mesh.vertex_layers()[v as usize];
        let (positions, faces) = (self.mesh.positions(), self.mesh.faces());
        // The surface the edit replaces, as it is now (a face around both ends comes twice,
        // which a nearest distance does not mind).
        let before: Vec<[Vec3; 3]> = carrying
            .iter()
            .map(|&f| faces[f as usize].map(|w| positions[w as usize]))
            .collect();
        // One gathering serves both tests: faces near the move (for the distance test) and near
        // the moved faces (for the crossing test).
        let reach = Aabb::of_points(&[from, target]).expanded(d);
        let around = bounds_of(moved).including_box(&reach);
        let near = self.gather_near(&around);
        let safe = self.keeps_collision_distance(v, (from, target, merged), &near);
        let involved: Vec<u32> = [Some(v), merged].into_iter().flatten().collect();

        let clear = safe
            && self.faces_clear_among(moved, &involved, &[], &near)
            && self.keeps_layer_gap(layer, &before, moved);
        self.near = near;
        clear
    }

    /// `check`'s verdict on an edit that makes `triangles` (and leaves the mesh's rim as it
    /// was, when `keeps_rim`), unless the sheet zone vouches for them (`zone`, counted): then
    /// `vouched`'s. An edit checked in full that passes ends the zone, since its faces may
    /// leave the zone no longer a sheet.
    fn unless_vouched(
        &mut self,
        triangles: &[IdTriangle],
        keeps_rim: bool,
        (vouched, check): (
            impl FnOnce(&mut Self) -> bool,
            impl FnOnce(&mut Self) -> bool,
        ),
    ) -> bool {
        let holds = |z: &super::zone::Zone| z.holds(triangles.iter().map(|(_, t)| t));
        if keeps_rim && self.zone.as_ref().is_some_and(holds) {
            self.report.culled += 1;
            return vouched(self);
        }
        let clear = check(self);
        if clear {
            self.zone = None;
        }
        clear
    }

    /// Flipping an edge replaces the two faces `before` by `after`: the new faces cross nothing
    /// and keep the layer gap.
    pub(super) fn flip_is_clear(
        &mut self,
        after: &[IdTriangle],
        replaced: [u32; 2],
        before: &[[Vec3; 3]],
    ) -> bool {
        // A flip's edge is never on the rim (a rim edge has one face).
        self.unless_vouched(
            after,
            true,
            (
                |_| true,
                |remesher| {
                    let layer = remesher.mesh.face_layers()[replaced[0] as usize];
                    let near = remesher.gather_near(&bounds_of(after));
                    let clear = remesher.faces_clear_among(after, &[], &replaced, &near)
                        && remesher.keeps_layer_gap(layer, before, after);
                    remesher.near = near;
                    clear
                },
            ),
        )
    }

    /// The layer gap kept through an edit that replaces the surface `before` (triangles of
    /// `layer`) by `after`: no vertex of another layer within the collision distance of `after`
    /// may be nearer to it than it was to `before`. The collision response keeps this for a
    /// stroke's moves (`collide::gap_guard`); without it here, relaxing and collapsing faces
    /// toward a still vertex of a layer beneath brought layers to 0.94·d. The vertices are
    /// found through the vertex grid, which every edit keeps filed where its vertices are.
    fn keeps_layer_gap(
        &self,
        layer: crate::mesh::LayerId,
        before: &[[Vec3; 3]],
        after: &[IdTriangle],
    ) -> bool {
        if self.mesh.layer_count() < 2 {
            return true;
        }
        let d = self.settings.collision_distance;
        let boxes: Vec<Aabb> = after.iter().map(|(_, t)| Aabb::of_points(t)).collect();
        let bounds = boxes.iter().fold(Aabb::EMPTY, |b, t| b.including_box(t));
        let nearest = |p: Vec3, triangles: &mut dyn Iterator<Item = &[Vec3; 3]>| {
            triangles
                .map(|&t| point_triangle_distance(p, t))
                .fold(f32::INFINITY, f32::min)
        };
        let (positions, layers) = (self.mesh.positions(), self.mesh.vertex_layers());
        let mut kept = true;
        let reach = bounds.expanded(d);
        self.grid.for_each_in_box(reach.min, reach.max, |w| {
            let p = positions[w as usize];
            if !kept || layers[w as usize] == layer || !bounds.within(p, d) {
                return;
            }
            let mut within_reach = after
                .iter()
                .zip(&boxes)
                .filter(|(_, b)| b.within(p, d))
                .map(|((_, t), _)| t);
            let now = nearest(p, &mut within_reach);
            kept = now >= d || now >= nearest(p, &mut before.iter());
        });
        kept
    }

    /// Splitting the edge opposite corner `c` puts the new vertex where floats round the
    /// edge's midpoint, a hair off the edge. Where surfaces are pressed together within the
    /// exclusion ring (a grab drawn into a needle), another face can lie within that hair of
    /// the two faces, and the halves would cross it or fold onto it: checked exactly, as a
    /// flip's faces are.
    pub(super) fn split_is_clear(&mut self, c: u32) -> bool {
        let mesh = &*self.mesh;
        let (a, b) = mesh.edge_vertices(c);
        let x = mesh.corner_vertex(c);
        let m = mesh.vertex_count() as u32;
        let p = |v: u32| mesh.positions()[v as usize];
        let at_m = p(a).lerp(p(b), SPLIT_AT);
        let o = mesh.adjacency().opposite[c as usize];
        // The faces across the edge, where it has them (the last two halves otherwise unused).
        let y = if o == INVALID {
            x
        } else {
            mesh.corner_vertex(o)
        };
        let all_halves = [
            ([x, a, m], [p(x), p(a), at_m]),
            ([x, m, b], [p(x), at_m, p(b)]),
            ([y, b, m], [p(y), p(b), at_m]),
            ([y, m, a], [p(y), at_m, p(a)]),
        ];
        let all_replaced = [c / 3, o / 3];
        let sides = if o == INVALID { 1 } else { 2 };
        let (halves, replaced) = (&all_halves[..2 * sides], &all_replaced[..sides]);
        let (ends, layer) = ((p(a), p(b)), mesh.vertex_layers()[a as usize]);
        self.unless_vouched(
            halves,
            o != INVALID,
            (
                |_| true,
                |remesher| {
                    // The halves lie on the faces they replace: only the new vertex needs the wider
                    // reach.
                    let mut reach = bounds_of(halves);
                    if remesher.mesh.layer_count() > 1 {
                        let d = remesher.settings.collision_distance;
                        reach = reach.including_box(&Aabb::of_points(&[at_m]).expanded(d));
                    }
                    let near = remesher.gather_near(&reach);
                    let clear = remesher.faces_clear_among(halves, &[], replaced, &near)
                        && remesher.midpoint_keeps_gap(layer, ends, at_m, &near);
                    remesher.near = near;
                    clear
                },
            ),
        )
    }

    /// A split's new vertex `m` on the edge `ends` is no nearer to another layer's face within
    /// the collision distance than the nearer end is: distance to a face is convex along the
    /// edge, so the midpoint of an edge that passes over another layer's ridge can be nearer
    /// than either end, and the vertex would show a gap the vertices never had.
    fn midpoint_keeps_gap(
        &self,
        layer: crate::mesh::LayerId,
        (a, b): (Vec3, Vec3),
        m: Vec3,
        near: &[NearFace],
    ) -> bool {
        let d = self.settings.collision_distance;
        let face_layers = self.mesh.face_layers();
        near.iter()
            .filter(|c| face_layers[c.face as usize] != layer && c.bounds.within(m, d))
            .all(|c| {
                let distance = |p: Vec3| point_triangle_distance(p, c.at);
                let now = distance(m);
                now >= d || now >= distance(a).min(distance(b))
            })
    }

    /// The faces filed near `query` (live ones, at their current positions), in the reusable
    /// list.
    fn gather_near(&mut self, query: &Aabb) -> Vec<NearFace> {
        let mut near = std::mem::take(&mut self.near);
        near.clear();
        let positions = self.mesh.positions();
        let faces = self.mesh.faces();
        self.surface.for_each_near(query, |face| {
            let ids = faces[face as usize];
            if ids[0] == INVALID {
                return;
            }
            let at = ids.map(|w| positions[w as usize]);
            let bounds = Aabb::of_points(&at);
            if bounds.overlaps(query) {
                near.push(NearFace {
                    face,
                    ids,
                    at,
                    bounds,
                });
            }
        });
        near
    }

    /// No triangle in `triangles` (vertex ids and the positions they will have) crosses a nearby
    /// face, of any layer, nor overlaps a neighbour beyond the vertices they share (a fold, which
    /// pair tests skip and a later split would turn into a crossing). Faces around a `moving`
    /// vertex are being tested themselves, among each other; `replaced` faces are on their way
    /// out.
    fn faces_clear_among(
        &self,
        triangles: &[IdTriangle],
        moving: &[u32],
        replaced: &[u32],
        near: &[NearFace],
    ) -> bool {
        for (i, (ids, tri)) in triangles.iter().enumerate() {
            for (other_ids, other) in &triangles[i + 1..] {
                let shared = ids.iter().filter(|w| other_ids.contains(w)).count();
                if shared == 3
                    || (shared > 0 && neighbours_overlap(*tri, *ids, *other, *other_ids))
                    || (shared == 0 && triangles_intersect(*tri, *other))
                {
                    return false;
                }
            }
        }
        for (ids, tri) in triangles {
            let bounds = Aabb::of_points(tri);
            for candidate in near {
                let (face, other_ids, other) = (candidate.face, candidate.ids, candidate.at);
                if !candidate.bounds.overlaps(&bounds)
                    || replaced.contains(&face)
                    || other_ids.iter().any(|w| moving.contains(w))
                {
                    continue;
                }
                let shared = other_ids.iter().filter(|w| ids.contains(w)).count();
                let crossing = match shared {
                    3 => false,
                    0 => triangles_intersect(*tri, other),
                    _ => neighbours_overlap(*tri, *ids, other, other_ids),
                };
                if crossing {
                    return false;
                }
            }
        }
        true
    }
}

/// The box around triangles given as (vertex ids, positions).
fn bounds_of(triangles: &[IdTriangle]) -> Aabb {
    triangles.iter().fold(Aabb::EMPTY, |b, (_, t)| {
        b.including(t[0]).including(t[1]).including(t[2])
    })
}
