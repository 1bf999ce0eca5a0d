//! Topology edits on the corner table: edge split, edge flip and edge collapse, each with the
//! topological predicate that keeps the mesh manifold (after pmp-library's `is_flip_ok` /
//! `is_collapse_ok`). Geometric conditions (normal flips, lengths, collisions) belong to the
//! caller, which knows the target edge length and the other layers.
//!
//! An edge is named by a corner `c`: the edge opposite it, from `next(c)`'s vertex to
//! `prev(c)`'s. Every edit keeps `validate()` passing; tests check that after each one.

use glam::Vec3;

use super::{INVALID, Mesh, VertexFlags, face_of, next, prev};

impl Mesh {
    /// The two end vertices of the edge opposite `corner`.
    pub fn edge_vertices(&self, corner: u32) -> (u32, u32) {
        (
            self.corner_vertex(next(corner)),
            self.corner_vertex(prev(corner)),
        )
    }

    /// A corner whose opposite edge is `(a, b)` in either direction, if the edge exists.
    pub fn find_edge(&self, a: u32, b: u32) -> Option<u32> {
        let first = self.adjacency.vertex_corner[a as usize];
        if first == INVALID {
            return None;
        }
        for c in self.adjacency.corners_around(a) {
            // Around `a`, corner c's face holds edges (a, next) and (prev, a).
            if self.corner_vertex(next(c)) == b {
                return Some(prev(c));
            }
            if self.corner_vertex(prev(c)) == b {
                return Some(next(c));
            }
        }
        None
    }

    /// Number of edges at a vertex.
    pub fn valence(&self, vertex: u32) -> usize {
        let corners = self.adjacency.corners_around(vertex).count();
        if self.is_boundary_vertex(vertex) {
            corners + 1
        } else {
            corners
        }
    }

    /// True when the edge opposite `corner` lies on a boundary.
    pub fn is_boundary_edge(&self, corner: u32) -> bool {
        self.adjacency.opposite[corner as usize] == INVALID
    }

    /// Re-points `vertex` at a corner of its fan that starts at a boundary, if it has one,
    /// beginning from `known`, a live corner of the vertex.
    pub(super) fn repair_vertex_corner(&mut self, vertex: u32, known: u32) {
        let mut c = known;
        for _ in 0..super::corner_table::MAX_FAN {
            let left = self.adjacency.swing_left(c);
            if left == INVALID || left == known {
                break;
            }
            c = left;
        }
        self.adjacency.vertex_corner[vertex as usize] = c;
    }

    /// Makes room for one more split (a vertex and two faces); a full array grows by an eighth
    /// ([`crate::grow`]). A mesh made or read calls it, so its arrays have an eighth's room and
    /// the first split of the first stroke copies nothing; room never used costs address
    /// space, not memory.
    pub(super) fn reserve_for_edits(&mut self) {
        use crate::grow::room_for as room;
        room(&mut self.positions, 1);
        room(&mut self.normals, 1);
        room(&mut self.brdfs, 1);
        room(&mut self.vertex_layers, 1);
        room(&mut self.flags, 1);
        room(&mut self.adjacency.vertex_corner, 1);
        room(&mut self.faces, 2);
        room(&mut self.face_layers, 2);
        room(&mut self.adjacency.opposite, 6);
    }

    pub(super) fn push_face(&mut self, vertices: [u32; 3], layer: u32) -> u32 {
        let f = self.faces.len() as u32;
        self.faces.push(vertices);
        self.face_layers.push(layer);
        self.adjacency.opposite.extend([INVALID; 3]);
        f
    }

    fn link(&mut self, a: u32, b: u32) {
        if a != INVALID {
            self.adjacency.opposite[a as usize] = b;
        }
        if b != INVALID {
            self.adjacency.opposite[b as usize] = a;
        }
    }

    /// Splits the edge opposite `corner` at `t` along it (0 at `next(corner)`'s vertex), adding
    /// one vertex and one or two faces. Attributes and the mask are interpolated; no other
    /// flag is set on the new vertex. Returns the new vertex.
    pub fn split_edge(&mut self, corner: u32, t: f32) -> u32 {
        let c0 = corner;
        let (c1, c2) = (next(c0), prev(c0));
        let (x, a, b) = (
            self.corner_vertex(c0),
            self.corner_vertex(c1),
            self.corner_vertex(c2),
        );
        let layer = self.face_layers[face_of(c0) as usize];
        let o = self.adjacency.opposite[c0 as usize];

        self.reserve_for_edits();
        let m = self.positions.len() as u32;
        let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
        self.positions.push(pa.lerp(pb, t));
        let na = self.normals[a as usize];
        let nb = self.normals[b as usize];
        self.normals
            .push(na.lerp(nb, t).try_normalize().unwrap_or(na));
        let (ba, bb) = (self.brdfs[a as usize], self.brdfs[b as usize]);
        self.brdfs.push(ba.lerp(&bb, t));
        self.vertex_layers.push(layer);
        // The mask is interpolated too: a split inside a masked region stays masked.
        let (fa, fb) = (self.flags[a as usize], self.flags[b as usize]);
        let mut flags = VertexFlags::empty();
        flags.set_mask(fa.mask() + (fb.mask() - fa.mask()) * t);
        self.flags.push(flags);
        self.adjacency.vertex_corner.push(INVALID);

        // Face f = [x, a, b] becomes [x, a, m]; the new face [x, m, b] takes the b side.
        let o1 = self.adjacency.opposite[c1 as usize];
        let f_index = face_of(c0) as usize;
        self.faces[f_index][(c2 % 3) as usize] = m;
        let f1 = self.push_face([x, m, b], layer);
        let (d0, d1, d2) = (3 * f1, 3 * f1 + 1, 3 * f1 + 2);
        self.link(d1, o1);
        self.link(d2, c1);

        if o != INVALID {
            // Face g = [y, b, a] becomes [y, b, m]; the new face [y, m, a] takes the a side.
            let (e0, e1, e2) = (o, next(o), prev(o));
            let y = self.corner_vertex(e0);
            let p1 = self.adjacency.opposite[e1 as usize];
            let g_index = face_of(e0) as usize;
            self.faces[g_index][(e2 % 3) as usize] = m;
            let g1 = self.push_face([y, m, a], layer);
            let (h0, h1, h2) = (3 * g1, 3 * g1 + 1, 3 * g1 + 2);
            self.link(h1, p1);
            self.link(h2, e1);
            self.link(c0, h0);
            self.link(d0, e0);
            self.repair_vertex_corner(y, e0);
            self.repair_vertex_corner(a, c1);
        } else {
            self.adjacency.opposite[c0 as usize] = INVALID;
            self.adjacency.opposite[d0 as usize] = INVALID;
            self.repair_vertex_corner(a, c1);
        }
        self.repair_vertex_corner(m, c2);
        self.repair_vertex_corner(x, c0);
        self.repair_vertex_corner(b, d2);
        self.version.topology = super::next_stamp();
        m
    }

    /// Whether the edge opposite `corner` can be flipped without breaking the mesh: it must be
    /// interior, and the new edge must not exist already.
    pub fn is_flip_ok(&self, corner: u32) -> bool {
        let o = self.adjacency.opposite[corner as usize];
        if o == INVALID {
            return false;
        }
        let (x, y) = (self.corner_vertex(corner), self.corner_vertex(o));
        x != y && self.find_edge(x, y).is_none()
    }

    /// Flips the edge opposite `corner` (check [`is_flip_ok`](Self::is_flip_ok) first): faces
    /// `[x, a, b]` and `[y, b, a]` become `[x, a, y]` and `[y, b, x]`.
    pub fn flip_edge(&mut self, corner: u32) {
        let (c0, c1, c2) = (corner, next(corner), prev(corner));
        let o = self.adjacency.opposite[c0 as usize];
        let (e0, e1, e2) = (o, next(o), prev(o));
        let (x, a, b, y) = (
            self.corner_vertex(c0),
            self.corner_vertex(c1),
            self.corner_vertex(c2),
            self.corner_vertex(e0),
        );
        let o1 = self.adjacency.opposite[c1 as usize];
        let p1 = self.adjacency.opposite[e1 as usize];
        let (f, g) = (face_of(c0) as usize, face_of(e0) as usize);
        self.faces[f][(c2 % 3) as usize] = y;
        self.faces[g][(e2 % 3) as usize] = x;
        self.link(c0, p1);
        self.link(e0, o1);
        self.link(c1, e1);
        for (v, known) in [(x, c0), (y, e0), (a, c1), (b, e1)] {
            self.repair_vertex_corner(v, known);
        }
        self.version.topology = super::next_stamp();
    }

    /// Whether collapsing the edge opposite `corner` (removing `prev(corner)`'s vertex into
    /// `next(corner)`'s) keeps the mesh a manifold: the link condition (the two ends share
    /// exactly the neighbours on the faces of the edge), no interior edge between two boundary
    /// vertices, and no neighbour left with fewer than three edges.
    pub fn is_collapse_ok(&self, corner: u32) -> bool {
        let (a, b) = self.edge_vertices(corner);
        let o = self.adjacency.opposite[corner as usize];
        let x = self.corner_vertex(corner);
        let y = if o == INVALID {
            INVALID
        } else {
            self.corner_vertex(o)
        };
        let boundary_edge = o == INVALID;
        if !boundary_edge && self.is_boundary_vertex(a) && self.is_boundary_vertex(b) {
            return false;
        }
        // A boundary vertex may only merge along its boundary.
        if !boundary_edge && self.is_boundary_vertex(b) {
            return false;
        }
        // Most fans are short: their rings are gathered on the stack, where this test runs
        // millions of times in a whole-mesh remesh.
        let (ring_a, ring_b) = (self.neighbours(a), self.neighbours(b));
        let shared = ring_a.iter().filter(|v| ring_b.contains(v)).count();
        let expected = if boundary_edge { 1 } else { 2 };
        if shared != expected || !ring_a.contains(&x) || (!boundary_edge && !ring_a.contains(&y)) {
            return false;
        }
        // The opposite vertices lose an edge; a closed fan needs at least three.
        for v in [x, y] {
            if v == INVALID {
                continue;
            }
            let minimum = if self.is_boundary_vertex(v) { 2 } else { 3 };
            if self.valence(v) <= minimum {
                return false;
            }
        }
        // The survivor must keep a fan: a tiny closed component would fold flat. (A ring holds
        // as many vertices as the valence counts edges.)
        ring_a.len() + ring_b.len() > 4 + expected
    }

    /// Collapses the edge opposite `corner` (check [`is_collapse_ok`](Self::is_collapse_ok)
    /// first): `prev(corner)`'s vertex `b` is removed into `next(corner)`'s vertex `a`, which
    /// moves to `position`; BRDFs are averaged. Returns the surviving vertex.
    pub fn collapse_edge(&mut self, corner: u32, position: Vec3) -> u32 {
        let (c0, c1, c2) = (corner, next(corner), prev(corner));
        let (x, a, b) = (
            self.corner_vertex(c0),
            self.corner_vertex(c1),
            self.corner_vertex(c2),
        );
        let o = self.adjacency.opposite[c0 as usize];
        let fan_b: Vec<u32> = self.adjacency.corners_around(b).collect();
        let f = face_of(c0);
        let g = if o == INVALID { INVALID } else { face_of(o) };

        // Stitch the faces across f's other two edges, and g's.
        let o1 = self.adjacency.opposite[c1 as usize];
        let o2 = self.adjacency.opposite[c2 as usize];
        // (`link` with a boundary on one side leaves the other side a boundary.)
        self.link(o1, o2);
        let mut y = INVALID;
        let (mut p1, mut p2) = (INVALID, INVALID);
        if o != INVALID {
            let (e1, e2) = (next(o), prev(o));
            y = self.corner_vertex(o);
            p1 = self.adjacency.opposite[e1 as usize];
            p2 = self.adjacency.opposite[e2 as usize];
            self.link(p1, p2);
        }
        // b's other faces now use a.
        for &c in &fan_b {
            let face = face_of(c);
            if face != f && face != g {
                self.faces[face as usize][(c % 3) as usize] = a;
            }
        }
        for dead in [f, g] {
            if dead == INVALID {
                continue;
            }
            self.faces[dead as usize] = [INVALID; 3];
            for k in 0..3 {
                self.adjacency.opposite[(3 * dead + k) as usize] = INVALID;
            }
        }
        self.positions[a as usize] = position;
        let merged = self.brdfs[a as usize].lerp(&self.brdfs[b as usize], 0.5);
        self.brdfs[a as usize] = merged;
        self.flags[b as usize] = VertexFlags::DEAD;
        self.adjacency.vertex_corner[b as usize] = INVALID;

        // Each affected vertex needs a live corner: one on a face across a stitched edge.
        let live_corner = |mesh: &Mesh, v: u32, candidates: &[u32]| {
            candidates
                .iter()
                .flat_map(|&k| [k, next(k), prev(k)])
                .find(|&k| {
                    k != INVALID
                        && !mesh.is_face_dead(face_of(k) as usize)
                        && mesh.corner_vertex(k) == v
                })
        };
        let around = [o1, o2, p1, p2];
        for v in [a, x, y] {
            if v == INVALID {
                continue;
            }
            let known = live_corner(self, v, &around).or_else(|| {
                fan_b.iter().copied().find(|&k| {
                    !self.is_face_dead(face_of(k) as usize) && self.corner_vertex(k) == v
                })
            });
            match known {
                Some(k) => self.repair_vertex_corner(v, k),
                None => {
                    // Nothing left around it (only possible on a lone face pair).
                    self.adjacency.vertex_corner[v as usize] = INVALID;
                    self.flags[v as usize].insert(VertexFlags::DEAD);
                }
            }
        }
        self.version.topology = super::next_stamp();
        a
    }
}
