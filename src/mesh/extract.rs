//! A mesh of some of another's layers: what `slayer convert --layers` writes.

use super::{INVALID, LayerId, Mesh, MeshError, VertexFlags};

impl Mesh {
    /// The live faces of `layers` (in that order, renumbered from 0) with their vertices, BRDFs
    /// and persistent flags (the mask). Layers are separate surfaces, so any choice of them is a
    /// valid mesh.
    pub fn with_layers(&self, layers: &[LayerId]) -> Result<Mesh, MeshError> {
        if let Some(&layer) = layers.iter().find(|&&l| l as usize >= self.layer_count()) {
            return Err(MeshError::LayerOutOfRange {
                face: 0,
                layer,
                layer_count: self.layer_count(),
            });
        }
        let mut new_layer = vec![INVALID; self.layer_count()];
        for (i, &l) in layers.iter().enumerate() {
            if let Some(slot) = new_layer.get_mut(l as usize) {
                *slot = i as LayerId;
            }
        }
        let mut new_vertex = vec![INVALID; self.vertex_count()];
        let mut kept_vertices = Vec::new();
        let mut faces = Vec::new();
        let mut face_layers = Vec::new();
        for (tri, &layer) in self.faces().iter().zip(self.face_layers()) {
            let to = new_layer[layer as usize];
            if tri[0] == INVALID || to == INVALID {
                continue;
            }
            faces.push(tri.map(|v| {
                if new_vertex[v as usize] == INVALID {
                    new_vertex[v as usize] = kept_vertices.len() as u32;
                    kept_vertices.push(v as usize);
                }
                new_vertex[v as usize]
            }));
            face_layers.push(to);
        }
        let names = layers
            .iter()
            .map(|&l| self.layer_names()[l as usize].clone())
            .collect();
        let positions = kept_vertices.iter().map(|&v| self.positions()[v]).collect();
        let mut mesh = Mesh::new(positions, faces, face_layers, names)?;
        mesh.set_brdfs(kept_vertices.iter().map(|&v| self.brdfs()[v]).collect())?;
        for (flag, &v) in mesh.flags_mut().iter_mut().zip(&kept_vertices) {
            *flag |= self.flags()[v] & VertexFlags::PERSISTENT;
        }
        Ok(mesh)
    }
}
