//! The topology of each connected component: open or closed, its boundary loops, its Euler
//! characteristic and genus. What `slayer check` reports per layer, and what the fuse policy's
//! tests count (a join adds a handle or merges two components; a split takes one away).

use serde::Serialize;

use super::components::DisjointSets;
use super::{INVALID, LayerId, Mesh};

/// One connected component's topology.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ComponentShape {
    pub layer: LayerId,
    pub faces: usize,
    pub vertices: usize,
    pub edges: usize,
    /// Closed curves of boundary edges; 0 for a closed component.
    pub boundary_loops: usize,
    /// V − E + F.
    pub euler: i64,
    /// Handles: (2 − χ − boundary loops) / 2 for an orientable surface (a sphere 0, a torus 1).
    pub genus: i64,
}

impl ComponentShape {
    pub fn is_closed(&self) -> bool {
        self.boundary_loops == 0
    }
}

impl Mesh {
    /// Every component's topology, in order of their first face (as [`Mesh::components`]).
    pub fn component_shapes(&self) -> Vec<ComponentShape> {
        let components = self.components();
        let count = components.count();
        let mut shapes: Vec<ComponentShape> = (0..count)
            .map(|i| ComponentShape {
                layer: components.layer[i],
                faces: components.size[i],
                vertices: 0,
                edges: 0,
                boundary_loops: 0,
                euler: 0,
                genus: 0,
            })
            .collect();
        let mut vertex_component = vec![INVALID; self.vertex_count()];
        // Boundary vertices joined along boundary edges: one set per loop.
        let mut loops = DisjointSets::new(self.vertex_count());
        let mut on_boundary = vec![false; self.vertex_count()];
        let opposite = &self.adjacency().opposite;
        for (face, tri) in self.faces().iter().enumerate() {
            let label = components.face_component[face];
            if label == INVALID {
                continue;
            }
            let shape = &mut shapes[label as usize];
            for (k, &v) in tri.iter().enumerate() {
                if vertex_component[v as usize] == INVALID {
                    vertex_component[v as usize] = label;
                    shape.vertices += 1;
                }
                // Corner k faces the edge from tri[k + 1] to tri[k + 2]: an interior edge is
                // seen from two corners, a boundary edge from one.
                if opposite[3 * face + k] == INVALID {
                    shape.edges += 2;
                    let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                    loops.union(a, b);
                    on_boundary[a as usize] = true;
                    on_boundary[b as usize] = true;
                } else {
                    shape.edges += 1;
                }
            }
        }
        for (v, _) in on_boundary.iter().enumerate().filter(|(_, b)| **b) {
            if loops.find(v as u32) == v as u32 {
                shapes[vertex_component[v] as usize].boundary_loops += 1;
            }
        }
        for shape in &mut shapes {
            shape.edges /= 2;
            shape.euler = shape.vertices as i64 - shape.edges as i64 + shape.faces as i64;
            shape.genus = (2 - shape.euler - shape.boundary_loops as i64) / 2;
        }
        shapes
    }
}
