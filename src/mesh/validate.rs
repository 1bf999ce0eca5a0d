//! `Mesh::validate`: every invariant the rest of the engine relies on, each failure naming the
//! element that broke. Tests call it after every topology edit (STYLE: a validator no test runs is
//! worse than none).

use super::{
    CornerTable, INVALID, MAX_COORDINATE, Mesh, MeshError, VertexFlags, face_of, next, prev,
};

impl Mesh {
    /// Checks attribute lengths, indices, layers, finiteness, the corner table's links and the
    /// manifoldness of every vertex. Dead elements are skipped.
    pub fn validate(&self) -> Result<(), MeshError> {
        self.validate_lengths()?;
        self.validate_faces()?;
        self.validate_vertices()?;
        self.validate_opposites()?;
        self.validate_vertex_corners()?;
        // Local checks passed; a fresh table from the faces alone must agree link for link,
        // which catches two faces sharing an edge without being linked.
        let rebuilt = CornerTable::build(&self.faces, self.vertex_count())?;
        if let Some(c) = (0..self.adjacency.opposite.len())
            .find(|&c| rebuilt.opposite[c] != self.adjacency.opposite[c])
        {
            return Err(MeshError::BrokenOpposite {
                corner: c,
                detail: format!(
                    "stored {} but the faces say {}",
                    show(self.adjacency.opposite[c]),
                    show(rebuilt.opposite[c])
                ),
            });
        }
        Ok(())
    }

    fn validate_lengths(&self) -> Result<(), MeshError> {
        let n = self.positions.len();
        let f = self.faces.len();
        let checks: [(&'static str, usize, usize); 7] = [
            ("normals", self.normals.len(), n),
            ("brdfs", self.brdfs.len(), n),
            ("vertex_layers", self.vertex_layers.len(), n),
            ("flags", self.flags.len(), n),
            ("vertex_corner", self.adjacency.vertex_corner.len(), n),
            ("face_layers", self.face_layers.len(), f),
            ("opposite", self.adjacency.opposite.len(), 3 * f),
        ];
        for (attribute, len, expected) in checks {
            if len != expected {
                return Err(MeshError::AttributeLength {
                    attribute,
                    len,
                    expected,
                });
            }
        }
        Ok(())
    }

    fn validate_faces(&self) -> Result<(), MeshError> {
        let vertex_count = self.vertex_count();
        for (face, tri) in self.faces.iter().enumerate() {
            if tri[0] == INVALID {
                continue;
            }
            let layer = self.face_layers[face];
            if layer as usize >= self.layer_count() {
                return Err(MeshError::LayerOutOfRange {
                    face,
                    layer,
                    layer_count: self.layer_count(),
                });
            }
            for (k, &v) in tri.iter().enumerate() {
                if v as usize >= vertex_count {
                    return Err(MeshError::IndexOutOfRange {
                        face,
                        corner: face * 3 + k,
                        vertex: v,
                        vertex_count,
                    });
                }
                if self.flags[v as usize].contains(VertexFlags::DEAD) {
                    return Err(MeshError::DeadVertexInFace { face, vertex: v });
                }
                if self.vertex_layers[v as usize] != layer {
                    return Err(MeshError::LayerMismatch {
                        face,
                        vertex: v,
                        face_layer: layer,
                        vertex_layer: self.vertex_layers[v as usize],
                    });
                }
                if tri[(k + 1) % 3] == v {
                    return Err(MeshError::DegenerateFace { face, vertex: v });
                }
            }
        }
        Ok(())
    }

    fn validate_vertices(&self) -> Result<(), MeshError> {
        for (v, p) in self.positions.iter().enumerate() {
            if self.flags[v].contains(VertexFlags::DEAD) {
                continue;
            }
            let vertex = v as u32;
            if !p.is_finite() {
                return Err(MeshError::NonFinitePosition {
                    vertex,
                    position: p.to_array(),
                });
            }
            if let Some(&value) = p.to_array().iter().find(|c| c.abs() > MAX_COORDINATE) {
                return Err(MeshError::CoordinateOutOfRange {
                    vertex,
                    value,
                    limit: MAX_COORDINATE,
                });
            }
            if !self.normals[v].is_finite() {
                return Err(MeshError::NonFiniteAttribute {
                    vertex,
                    attribute: "normal",
                });
            }
            if !self.brdfs[v].is_finite() {
                return Err(MeshError::NonFiniteAttribute {
                    vertex,
                    attribute: "BRDF",
                });
            }
        }
        Ok(())
    }

    fn validate_opposites(&self) -> Result<(), MeshError> {
        let opposite = &self.adjacency.opposite;
        for c in 0..opposite.len() as u32 {
            if self.is_face_dead(face_of(c) as usize) {
                continue;
            }
            let o = opposite[c as usize];
            if o == INVALID {
                continue;
            }
            let broken = |detail: String| MeshError::BrokenOpposite {
                corner: c as usize,
                detail,
            };
            if o as usize >= opposite.len() {
                return Err(broken(format!("points past the end, to corner {o}")));
            }
            if self.is_face_dead(face_of(o) as usize) {
                return Err(broken(format!("points into dead face {}", face_of(o))));
            }
            if face_of(o) == face_of(c) {
                return Err(broken(format!("points into its own face, corner {o}")));
            }
            if opposite[o as usize] != c {
                return Err(broken(format!(
                    "corner {o} points back to {} instead",
                    show(opposite[o as usize])
                )));
            }
            let here = (self.corner_vertex(next(c)), self.corner_vertex(prev(c)));
            let there = (self.corner_vertex(prev(o)), self.corner_vertex(next(o)));
            if here != there {
                return Err(broken(format!(
                    "edge {here:?} faces edge {there:?} of corner {o}"
                )));
            }
        }
        Ok(())
    }

    fn validate_vertex_corners(&self) -> Result<(), MeshError> {
        let mut incidence = vec![0u32; self.vertex_count()];
        for tri in self.faces.iter().filter(|t| t[0] != INVALID) {
            for &v in tri {
                incidence[v as usize] += 1;
            }
        }
        for (v, &incident) in incidence.iter().enumerate() {
            if self.flags[v].contains(VertexFlags::DEAD) {
                continue;
            }
            let vertex = v as u32;
            let c = self.adjacency.vertex_corner[v];
            if incident == 0 {
                return Err(MeshError::IsolatedVertex { vertex });
            }
            let broken = |detail: String| MeshError::BrokenVertexCorner { vertex, detail };
            if c == INVALID || c as usize >= self.adjacency.opposite.len() {
                return Err(broken(format!("corner {} is not a corner", show(c))));
            }
            if self.is_face_dead(face_of(c) as usize) || self.corner_vertex(c) != vertex {
                return Err(broken(format!("corner {c} belongs to another vertex")));
            }
            // A fan walk must end where the boundary ends, and see every incident corner.
            let walked = self.adjacency.fan_len(c);
            if walked != incident {
                let has_boundary = self
                    .adjacency
                    .corners_around(vertex)
                    .any(|k| self.adjacency.swing_right(k) == INVALID);
                if has_boundary && self.adjacency.swing_left(c) != INVALID {
                    return Err(broken(format!(
                        "corner {c} is not the first of its boundary fan"
                    )));
                }
                return Err(MeshError::NonManifoldVertex { vertex });
            }
        }
        Ok(())
    }
}

fn show(corner: u32) -> String {
    if corner == INVALID {
        "none".to_string()
    } else {
        corner.to_string()
    }
}

#[cfg(test)]
mod tests {
    //! Corrupting the private links directly: each corruption is caught and names the element.
    use super::*;
    use crate::scene::shapes;

    #[test]
    fn broken_opposite_link_is_named() {
        let mut mesh = shapes::octahedron();
        let o = mesh.adjacency.opposite[0];
        mesh.adjacency.opposite[0] = INVALID;
        match mesh.validate() {
            Err(MeshError::BrokenOpposite { corner, .. }) => {
                assert!(corner == o as usize || corner == 0)
            }
            other => panic!("expected a broken opposite, got {other:?}"),
        }
    }

    #[test]
    fn opposite_pointing_at_the_wrong_edge_is_named() {
        let mut mesh = shapes::octahedron();
        let (a, b) = (mesh.adjacency.opposite[0], mesh.adjacency.opposite[1]);
        mesh.adjacency.opposite[0] = b;
        mesh.adjacency.opposite[1] = a;
        assert!(matches!(
            mesh.validate(),
            Err(MeshError::BrokenOpposite { corner: 0, .. })
        ));
    }

    #[test]
    fn vertex_corner_of_another_vertex_is_named() {
        let mut mesh = shapes::tetrahedron();
        mesh.adjacency.vertex_corner[2] = mesh.adjacency.vertex_corner[1];
        assert!(matches!(
            mesh.validate(),
            Err(MeshError::BrokenVertexCorner { vertex: 2, .. })
        ));
    }

    #[test]
    fn boundary_vertex_must_start_its_fan() {
        let mut mesh = shapes::fan(6);
        // Vertex 1 sits on the rim in faces 0 and 5; store the corner that does not start the fan.
        let start = mesh.adjacency.vertex_corner[1];
        let other = mesh.adjacency.swing_right(start);
        assert_ne!(other, INVALID);
        mesh.adjacency.vertex_corner[1] = other;
        assert!(matches!(
            mesh.validate(),
            Err(MeshError::BrokenVertexCorner { vertex: 1, .. })
        ));
    }

    #[test]
    fn wrong_attribute_length_is_named() {
        let mut mesh = shapes::triangle();
        mesh.normals.pop();
        assert!(matches!(
            mesh.validate(),
            Err(MeshError::AttributeLength {
                attribute: "normals",
                ..
            })
        ));
    }

    #[test]
    fn live_face_on_dead_vertex_is_named() {
        let mut mesh = shapes::tetrahedron();
        mesh.flags[3].insert(VertexFlags::DEAD);
        assert!(matches!(
            mesh.validate(),
            Err(MeshError::DeadVertexInFace { vertex: 3, .. })
        ));
    }
}
