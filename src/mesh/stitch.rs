//! New faces sewn into holes (the topology changes of `crate::topology`: a tube bridging two
//! holes, a cap closing one). The new faces link to each other and to the boundary edges of
//! the mesh they meet, so a hole whose every edge is met is closed.

use std::collections::{HashMap, HashSet};

use glam::Vec3;

use super::{Brdf, INVALID, LayerId, Mesh, MeshError, VertexFlags, face_of, next};

impl Mesh {
    /// Adds a vertex at `position` on `layer` with `brdf`, on no face yet (the caller's
    /// [`add_faces`](Mesh::add_faces) gives it some).
    pub fn push_vertex(&mut self, position: Vec3, brdf: Brdf, layer: LayerId) -> u32 {
        self.reserve_for_edits();
        let v = self.positions.len() as u32;
        self.positions.push(position);
        self.normals.push(Vec3::Z);
        self.brdfs.push(brdf);
        self.vertex_layers.push(layer);
        self.flags.push(VertexFlags::empty());
        self.adjacency.vertex_corner.push(INVALID);
        v
    }

    /// Adds `faces` (live vertices of `layer`, consistently wound) and links every edge of
    /// theirs to the new face or the boundary edge of the mesh that runs the other way. An
    /// edge met by neither stays a boundary. Refused, with the mesh unchanged, where a new
    /// edge would be a third face on an edge, or run the same way as a face it meets.
    pub fn add_faces(&mut self, faces: &[[u32; 3]], layer: LayerId) -> Result<(), MeshError> {
        let first = self.faces.len();
        // Directed edge (from, to) of the new faces → the corner opposite it.
        let mut new_edges: HashMap<(u32, u32), u32> = HashMap::new();
        for (i, tri) in faces.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| !self.is_vertex_live_or_new(v, layer)) {
                return Err(MeshError::NonManifoldVertex { vertex: v });
            }
            for k in 0..3 {
                let corner = (3 * (first + i) + k) as u32;
                let edge = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                if new_edges.insert(edge, corner).is_some() {
                    return Err(MeshError::InconsistentOrientation {
                        a: edge.0,
                        b: edge.1,
                        face_a: first + i,
                        face_b: first + i,
                    });
                }
            }
        }
        let mut links = Vec::new();
        for (&(a, b), &corner) in &new_edges {
            if new_edges.contains_key(&(b, a)) {
                continue;
            }
            if let Some(c) = self.find_edge(a, b) {
                // The old face must hold (b, a) and be open there.
                if self.adjacency.opposite[c as usize] != INVALID {
                    return Err(MeshError::NonManifoldEdge { a, b, faces: 3 });
                }
                if self.edge_vertices(c) != (b, a) {
                    return Err(MeshError::InconsistentOrientation {
                        a,
                        b,
                        face_a: super::face_of(c) as usize,
                        face_b: super::face_of(corner) as usize,
                    });
                }
                links.push((corner, c));
            }
        }
        for tri in faces {
            self.push_face(*tri, layer);
        }
        for (&(a, b), &corner) in &new_edges {
            if let Some(&other) = new_edges.get(&(b, a)) {
                self.adjacency.opposite[corner as usize] = other;
            }
        }
        for (corner, c) in links {
            self.adjacency.opposite[corner as usize] = c;
            self.adjacency.opposite[c as usize] = corner;
        }
        for (i, tri) in faces.iter().enumerate() {
            for (k, &v) in tri.iter().enumerate() {
                self.flags[v as usize].remove(VertexFlags::DEAD);
                self.repair_vertex_corner(v, (3 * (first + i) + k) as u32);
            }
        }
        self.version.topology = super::next_stamp();
        Ok(())
    }

    /// Removes `faces` at once, leaving holes; vertices left without a face die. Unlike
    /// [`kill_face`](Mesh::kill_face) one by one, it reads every fan while it is whole, so a
    /// vertex whose fan is cut in two on the way (a ring of faces removed around it) keeps
    /// what remains.
    pub fn cut_out(&mut self, faces: &[u32]) {
        let doomed: HashSet<u32> = faces.iter().copied().collect();
        let mut touched: Vec<u32> = faces.iter().flat_map(|&f| self.faces[f as usize]).collect();
        touched.sort_unstable();
        touched.dedup();
        let fans: Vec<Vec<u32>> = touched
            .iter()
            .map(|&v| self.adjacency.corners_around(v).collect())
            .collect();
        for &f in faces {
            for c in 3 * f..3 * f + 3 {
                let o = self.adjacency.opposite[c as usize];
                if o != INVALID {
                    self.adjacency.opposite[o as usize] = INVALID;
                }
                self.adjacency.opposite[c as usize] = INVALID;
            }
            self.faces[f as usize] = [INVALID; 3];
        }
        for (&v, fan) in touched.iter().zip(&fans) {
            let mut remaining = fan
                .iter()
                .copied()
                .filter(|&c| !doomed.contains(&face_of(c)));
            let first = remaining.clone().next();
            // A fan starts where turning left meets a boundary.
            let start = remaining.find(|&c| self.adjacency.opposite[next(c) as usize] == INVALID);
            match start.or(first) {
                Some(c) => self.adjacency.vertex_corner[v as usize] = c,
                None => {
                    self.adjacency.vertex_corner[v as usize] = INVALID;
                    self.flags[v as usize].insert(VertexFlags::DEAD);
                }
            }
        }
        self.version.topology = super::next_stamp();
    }

    fn is_vertex_live_or_new(&self, v: u32, layer: LayerId) -> bool {
        (v as usize) < self.vertex_count()
            && self.vertex_layers[v as usize] == layer
            && (self.is_vertex_live(v) || self.adjacency.vertex_corner[v as usize] == INVALID)
    }
}
