//! A content digest of a mesh: the same surfaces, materials, masks and layers give the same
//! digest however they were stored (PLY, OBJ with its materials, the session file) and whatever
//! dead rows an edit left behind.

use super::{INVALID, Mesh, VertexFlags};

impl Mesh {
    /// BLAKE3 over the live vertices in order (position, BRDF, layer, mask with its partial level) and the live faces
    /// in order (corners renumbered over the live vertices, layer), and the layer names. Normals
    /// are left out: they are derived from the positions, and readers recompute them.
    pub fn digest(&self) -> String {
        // One buffer hashed at once: a call per field would cost more than the hashing.
        let mut bytes: Vec<u8> =
            Vec::with_capacity(self.vertex_count() * 48 + self.face_count() * 16);
        let mut live_index = vec![INVALID; self.vertex_count()];
        let mut live = 0u32;
        for (v, index) in live_index.iter_mut().enumerate() {
            if !self.is_vertex_live(v as u32) {
                continue;
            }
            *index = live;
            live += 1;
            bytes.extend_from_slice(bytemuck::bytes_of(&self.positions[v]));
            bytes.extend_from_slice(bytemuck::bytes_of(&self.brdfs[v]));
            bytes.extend_from_slice(&self.vertex_layers[v].to_le_bytes());
            let mask = self.flags[v] & VertexFlags::PERSISTENT;
            bytes.extend_from_slice(&mask.bits().to_le_bytes());
        }
        bytes.extend_from_slice(&live.to_le_bytes());
        for (tri, layer) in self.faces.iter().zip(&self.face_layers) {
            if tri[0] == INVALID {
                continue;
            }
            for &v in tri {
                bytes.extend_from_slice(&live_index[v as usize].to_le_bytes());
            }
            bytes.extend_from_slice(&layer.to_le_bytes());
        }
        for name in &self.layer_names {
            bytes.extend_from_slice(&(name.len() as u64).to_le_bytes());
            bytes.extend_from_slice(name.as_bytes());
        }
        blake3::hash(&bytes).to_hex().to_string()
    }
}
