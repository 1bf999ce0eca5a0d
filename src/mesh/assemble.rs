//! Whole pieces in and out of a mesh: a set of faces copied out as a mesh of its own, a mesh
//! appended as new layers, faces and layers removed. The layer tools (`crate::tools`) are built
//! on these; each keeps the mesh manifold because layers never share a vertex.

use glam::Vec3;

use super::{INVALID, LayerId, Mesh, MeshError, VertexFlags};

impl Mesh {
    /// The live faces in `faces` as a one-layer mesh named `name`, with their BRDFs, and for
    /// each of its vertices the vertex of `self` it was copied from. Fails where the faces do
    /// not make a manifold surface on their own (two fans of the selection meeting at one
    /// vertex), naming the vertex of the copy.
    pub fn extract_faces(&self, faces: &[u32], name: &str) -> Result<(Mesh, Vec<u32>), MeshError> {
        // The new index of each face kept; a face named twice is left to `Mesh::new` to refuse.
        let mut kept = vec![INVALID; self.face_count()];
        let mut named_twice = false;
        let mut new_vertex = vec![INVALID; self.vertex_count()];
        let mut sources = Vec::new();
        let mut tris = Vec::with_capacity(faces.len());
        for &f in faces {
            if self.is_face_dead(f as usize) {
                continue;
            }
            named_twice |= kept[f as usize] != INVALID;
            kept[f as usize] = tris.len() as u32;
            tris.push(self.faces[f as usize].map(|v| {
                if new_vertex[v as usize] == INVALID {
                    new_vertex[v as usize] = sources.len() as u32;
                    sources.push(v);
                }
                new_vertex[v as usize]
            }));
        }
        let positions: Vec<Vec3> = sources
            .iter()
            .map(|&v| self.positions[v as usize])
            .collect();
        let layers = vec![0; tris.len()];
        let mut piece = if named_twice {
            Mesh::new(positions, tris, layers, vec![name.to_string()])?
        } else {
            // Faces of a valid mesh: every vertex used, no index repeated, one layer.
            let adjacency = self.adjacency.restricted(&kept, &tris, sources.len())?;
            let vertex_layers = vec![0; sources.len()];
            let names = vec![name.to_string()];
            Mesh::from_checked((positions, vertex_layers), (tris, layers), adjacency, names)
        };
        piece.set_brdfs(sources.iter().map(|&v| self.brdfs[v as usize]).collect())?;
        Ok((piece, sources))
    }

    /// Appends every live face and vertex of `piece` as new layers after the last (named as
    /// in `piece`), with its BRDFs and masks. Returns the first new layer. The piece shares no
    /// vertex with the mesh, so the two corner tables join by offsetting alone.
    pub fn append(&mut self, piece: &Mesh) -> LayerId {
        let mut piece = piece.clone();
        piece.compact();
        let first_layer = self.layer_count() as LayerId;
        let (vertex_base, corner_base) = (self.vertex_count() as u32, 3 * self.face_count() as u32);
        let shift_corner = |c: u32| {
            if c == INVALID {
                INVALID
            } else {
                c + corner_base
            }
        };
        self.positions.extend_from_slice(&piece.positions);
        self.normals.extend_from_slice(&piece.normals);
        self.brdfs.extend_from_slice(&piece.brdfs);
        self.vertex_layers
            .extend(piece.vertex_layers.iter().map(|&l| l + first_layer));
        self.flags
            .extend(piece.flags.iter().map(|&f| f & VertexFlags::PERSISTENT));
        self.faces
            .extend(piece.faces.iter().map(|t| t.map(|v| v + vertex_base)));
        self.face_layers
            .extend(piece.face_layers.iter().map(|&l| l + first_layer));
        let table = &mut self.adjacency;
        table
            .opposite
            .extend(piece.adjacency.opposite.iter().map(|&c| shift_corner(c)));
        table.vertex_corner.extend(
            piece
                .adjacency
                .vertex_corner
                .iter()
                .map(|&c| shift_corner(c)),
        );
        self.layer_names.extend(piece.layer_names.iter().cloned());
        self.version.topology = super::next_stamp();
        self.version.positions = super::next_stamp();
        self.version.attributes = super::next_stamp();
        self.version.flags = super::next_stamp();
        first_layer
    }

    /// Removes the faces for which `doomed[face]` holds, and the vertices left without a face,
    /// then compacts the mesh. Removing whole components (or whole layers) keeps it manifold;
    /// removing part of a surface is the caller's to keep manifold.
    pub fn remove_faces(&mut self, doomed: &[bool]) -> super::Compaction {
        let table = &self.adjacency;
        // Whole components (what the layer tools remove) border nothing that stays: their
        // rows are simply cleared. Anything else is unlinked face by face.
        let closed = (0..self.face_count()).filter(|&f| doomed[f]).all(|f| {
            (0..3).all(|k| {
                let o = table.opposite[3 * f + k];
                o == INVALID || doomed[o as usize / 3]
            })
        });
        for (face, _) in doomed.iter().enumerate().filter(|(_, doomed)| **doomed) {
            if self.is_face_dead(face) {
                continue;
            }
            if !closed {
                self.kill_face(face);
                continue;
            }
            for v in self.faces[face] {
                self.flags[v as usize].insert(VertexFlags::DEAD);
                self.adjacency.vertex_corner[v as usize] = INVALID;
            }
            self.adjacency.opposite[3 * face..3 * face + 3].fill(INVALID);
            self.faces[face] = [INVALID; 3];
        }
        self.compact()
    }

    /// Removes a layer: its faces and vertices, and its name; the layers after it move down
    /// by one. A `layer` past the last is ignored.
    pub fn remove_layer(&mut self, layer: LayerId) {
        if layer as usize >= self.layer_count() {
            return;
        }
        let doomed: Vec<bool> = self.face_layers.iter().map(|&l| l == layer).collect();
        self.remove_faces(&doomed);
        let renumber = |l: &mut LayerId| {
            if *l > layer {
                *l -= 1;
            }
        };
        self.face_layers.iter_mut().for_each(renumber);
        self.vertex_layers.iter_mut().for_each(renumber);
        self.layer_names.remove(layer as usize);
        self.version.attributes = super::next_stamp();
    }
}
