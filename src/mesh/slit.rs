//! Cutting a surface open along a path of edges (the cut tool, `crate::tools`): every edge of
//! the path becomes two boundary edges, and every vertex on it one vertex per wedge of its
//! fan that the path's edges divide.

use std::collections::HashSet;

use super::{INVALID, Mesh, VertexFlags, face_of, next};

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

impl Mesh {
    /// Cuts the mesh open along `edges` (vertex pairs). Pairs that are no edge, or a boundary
    /// edge already, are skipped. A vertex whose fan the cut divides into `k` wedges becomes
    /// `k` vertices: the first wedge keeps it, each other one gets a copy (same position and
    /// attributes). The end of a cut inside the surface divides nothing: it stays one vertex,
    /// now on the boundary of the slit. Returns each copy made, as (original, copy).
    pub fn split_along(&mut self, edges: &[[u32; 2]]) -> Vec<[u32; 2]> {
        let mut cut = HashSet::new();
        let mut cut_corners = Vec::new();
        for &[a, b] in edges {
            let Some(c) = self.find_edge(a, b) else {
                continue;
            };
            if self.adjacency.opposite[c as usize] != INVALID && cut.insert(key(a, b)) {
                cut_corners.push(c);
            }
        }
        let mut on_cut: Vec<u32> = cut.iter().flat_map(|&(a, b)| [a, b]).collect();
        on_cut.sort_unstable();
        on_cut.dedup();
        // Wedges first, for every vertex, while the fans are whole.
        let plans: Vec<(u32, Vec<Vec<u32>>)> =
            on_cut.iter().map(|&v| (v, self.wedges(v, &cut))).collect();
        let mut copies = Vec::new();
        for (v, wedges) in &plans {
            for wedge in &wedges[1..] {
                let copy = self.push_vertex_copy(*v);
                for &c in wedge {
                    self.faces[face_of(c) as usize][(c % 3) as usize] = copy;
                }
                self.adjacency.vertex_corner[copy as usize] = wedge[0];
                copies.push([*v, copy]);
            }
        }
        for c in cut_corners {
            let o = self.adjacency.opposite[c as usize];
            self.adjacency.opposite[c as usize] = INVALID;
            self.adjacency.opposite[o as usize] = INVALID;
        }
        for (v, wedges) in &plans {
            self.adjacency.vertex_corner[*v as usize] = wedges[0][0];
        }
        self.version.topology = super::next_stamp();
        copies
    }

    /// The corners around `v` in fan order, divided into wedges where the walk crosses a cut
    /// edge. Each wedge starts just after a cut (or at the fan's start on the mesh's rim), so
    /// its first corner starts the fan of the vertex the wedge becomes.
    fn wedges(&self, v: u32, cut: &HashSet<(u32, u32)>) -> Vec<Vec<u32>> {
        let mut corners: Vec<u32> = self.adjacency.corners_around(v).collect();
        // Turning right from corner c crosses the edge from v to next(c)'s vertex.
        let crosses_cut = |c: u32| cut.contains(&key(v, self.corner_vertex(next(c))));
        if !self.is_boundary_vertex(v)
            && let Some(first) = corners.iter().position(|&c| crosses_cut(c))
        {
            corners.rotate_left(first + 1);
        }
        let mut wedges = vec![Vec::new()];
        for (i, &c) in corners.iter().enumerate() {
            wedges.last_mut().expect("one wedge at least").push(c);
            if crosses_cut(c) && i + 1 < corners.len() {
                wedges.push(Vec::new());
            }
        }
        wedges
    }

    /// A new vertex with `v`'s position and attributes (its mask, no other flag), on no face
    /// yet.
    fn push_vertex_copy(&mut self, v: u32) -> u32 {
        self.reserve_for_edits();
        let i = v as usize;
        let copy = self.positions.len() as u32;
        self.positions.push(self.positions[i]);
        self.normals.push(self.normals[i]);
        self.brdfs.push(self.brdfs[i]);
        self.vertex_layers.push(self.vertex_layers[i]);
        self.flags.push(self.flags[i] & VertexFlags::PERSISTENT);
        self.adjacency.vertex_corner.push(INVALID);
        copy
    }
}
