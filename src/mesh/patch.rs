//! Patches of a mesh worked on apart and put back: whole-mesh remeshing (`crate::remesh`) copies
//! out slabs of the mesh far enough apart that nothing done inside one can reach another,
//! remeshes them on separate threads, and puts them back one after another.
//!
//! A patch's copy keeps every layer, vertex datum and flag of its faces, and their order: face
//! `i` of the copy is `faces[i]` of the mesh, vertex `i` is `sources[i]` (vertices the work adds
//! come after). Putting back leaves the faces the copy's work never reached (its rim and the
//! faces around it) exactly as they were, so the copy's cut edges rejoin the rest of the mesh
//! without a search; where they did change, the put-back refuses and the mesh is unchanged.

use rustc_hash::FxHashMap;

use super::{INVALID, Mesh, MeshError, VertexFlags, face_of};

/// A copy of some of a mesh's faces, to be worked on and put back ([`Mesh::put_back`]).
#[derive(Debug, Clone)]
pub struct Patch {
    /// The copy, its first `sources.len()` vertices and first `faces.len()` faces copied.
    pub mesh: Mesh,
    /// The mesh's vertex each of the copy's first vertices was copied from.
    pub sources: Vec<u32>,
    /// The mesh's faces the copy was made of, in the copy's order.
    pub faces: Vec<u32>,
    /// `sources` the other way: the copy's vertex of each copied vertex of the mesh.
    copies: FxHashMap<u32, u32>,
}

impl Patch {
    /// The copy's vertex copied from the mesh's vertex `v`, if the copy holds it.
    pub fn copy_of(&self, v: u32) -> Option<u32> {
        self.copies.get(&v).copied()
    }
}

/// Why patches could not be put back.
#[derive(Debug, thiserror::Error)]
pub enum PutBackError {
    /// The work changed a patch's rim, which only the whole mesh can rejoin.
    #[error("a patch's work reached its rim at vertex {vertex} of the mesh")]
    RimChanged { vertex: u32 },
    /// Two patches were copies of one face.
    #[error("two patches hold face {face}")]
    Overlap { face: u32 },
}

impl Mesh {
    /// A copy of every live face with a vertex in `vertices`, and of whatever more faces keep
    /// the copy manifold: a vertex of the copy's rim whose faces in the copy would make two
    /// fans brings all its faces (then its neighbours are checked in turn).
    pub fn copy_patch(&self, vertices: &[u32]) -> Result<Patch, MeshError> {
        // Each face's index in the copy (`INVALID`: not taken), as `restricted` wants it.
        let mut kept = vec![INVALID; self.face_count()];
        let mut faces = Vec::new();
        let take_fan = |v: u32, kept: &mut Vec<u32>, faces: &mut Vec<u32>| {
            for f in self.faces_around(v) {
                if kept[f as usize] == INVALID {
                    kept[f as usize] = faces.len() as u32;
                    faces.push(f);
                }
            }
        };
        for &v in vertices {
            take_fan(v, &mut kept, &mut faces);
        }
        let mut checked = 0;
        let mut whole: rustc_hash::FxHashSet<u32> = vertices.iter().copied().collect();
        while checked < faces.len() {
            let f = faces[checked];
            checked += 1;
            for v in self.faces[f as usize] {
                if !whole.contains(&v) && self.fans_in(v, &kept) > 1 {
                    whole.insert(v);
                    take_fan(v, &mut kept, &mut faces);
                }
            }
        }
        self.copy_faces(faces, &kept)
    }

    /// How many separate runs of `kept` faces lie around `v`.
    fn fans_in(&self, v: u32, kept: &[u32]) -> usize {
        let around: Vec<bool> = self
            .faces_around(v)
            .map(|f| kept[f as usize] != INVALID)
            .collect();
        let starts = (0..around.len())
            .filter(|&i| {
                let before = if i > 0 {
                    around[i - 1]
                } else {
                    // A closed fan wraps around; a boundary fan starts fresh.
                    !self.is_boundary_vertex(v) && around[around.len() - 1]
                };
                around[i] && !before
            })
            .count();
        // A closed fan entirely taken has no start, and is one fan.
        starts.max(usize::from(around.iter().all(|&t| t)))
    }

    /// The copy of `faces` (`kept` maps each to its index among them).
    fn copy_faces(&self, faces: Vec<u32>, kept: &[u32]) -> Result<Patch, MeshError> {
        let mut copies: FxHashMap<u32, u32> = FxHashMap::default();
        let mut sources = Vec::new();
        let tris: Vec<[u32; 3]> = faces
            .iter()
            .map(|&f| {
                self.faces[f as usize].map(|v| {
                    *copies.entry(v).or_insert_with(|| {
                        sources.push(v);
                        sources.len() as u32 - 1
                    })
                })
            })
            .collect();
        let adjacency = self.adjacency.restricted(kept, &tris, sources.len())?;
        let mut mesh = Mesh {
            positions: sources
                .iter()
                .map(|&v| self.positions[v as usize])
                .collect(),
            normals: sources.iter().map(|&v| self.normals[v as usize]).collect(),
            brdfs: sources.iter().map(|&v| self.brdfs[v as usize]).collect(),
            vertex_layers: sources
                .iter()
                .map(|&v| self.vertex_layers[v as usize])
                .collect(),
            flags: sources.iter().map(|&v| self.flags[v as usize]).collect(),
            face_layers: faces
                .iter()
                .map(|&f| self.face_layers[f as usize])
                .collect(),
            faces: tris,
            adjacency,
            layer_names: self.layer_names.clone(),
            version: super::MeshVersion::fresh(),
        };
        mesh.reserve_for_edits();
        Ok(Patch {
            mesh,
            sources,
            faces,
            copies,
        })
    }

    /// Puts worked-on patches back, in order: each copied vertex takes the copy's data, the
    /// copy's new vertices and faces are appended, its rewired faces take their slots. Returns,
    /// for each patch, the vertex of the mesh each of the copy's vertices now is (`INVALID` for
    /// a new vertex the work removed again). The patches must not share a face. Refused, with
    /// the mesh unchanged, where a patch's rim changed or two patches share a face.
    pub fn put_back(&mut self, patches: &[Patch]) -> Result<Vec<Vec<u32>>, PutBackError> {
        let mut owner = vec![INVALID; self.face_count()];
        for (p, patch) in patches.iter().enumerate() {
            for &f in &patch.faces {
                if owner[f as usize] != INVALID {
                    return Err(PutBackError::Overlap { face: f });
                }
                owner[f as usize] = p as u32;
            }
        }
        // Each patch's rim, found while the mesh's fans still run as they did.
        let rims: Vec<Vec<bool>> = (patches.iter().enumerate())
            .map(|(p, patch)| self.rim_of(patch, |f| owner[f as usize] == p as u32))
            .collect();
        for (patch, on_rim) in patches.iter().zip(&rims) {
            self.check_rim(patch, on_rim)?;
        }
        let maps = (patches.iter().enumerate())
            .map(|(p, patch)| {
                // Appended faces belong to no patch: they lie past `owner`'s end.
                let in_patch = |f: u32| owner.get(f as usize) == Some(&(p as u32));
                self.put_back_one(patch, (in_patch, &rims[p]))
            })
            .collect();
        self.version = super::MeshVersion::fresh();
        Ok(maps)
    }

    /// Whether the copy's rim is as it was: every face of the copy around a rim vertex (one
    /// with a face outside the patch), with its vertices where they were, and no new face at
    /// one. Then the rim vertices' fans, which run on outside the copy, still join.
    fn check_rim(&self, patch: &Patch, on_rim: &[bool]) -> Result<(), PutBackError> {
        let copy = &patch.mesh;
        let copied = patch.sources.len();
        let local_on_rim = |l: u32| (l as usize) < copied && on_rim[l as usize];
        let on_rim_in_mesh = |v: &u32| patch.copy_of(*v).is_some_and(local_on_rim);
        for f in 0..copy.face_count() {
            let now = copy.faces[f];
            let live = !copy.is_face_dead(f);
            let at_rim_now = live && now.iter().any(|&l| local_on_rim(l));
            let Some(&g) = patch.faces.get(f) else {
                if at_rim_now {
                    return Err(PutBackError::RimChanged {
                        vertex: patch.sources[now[0] as usize],
                    });
                }
                continue;
            };
            let was = self.faces[g as usize];
            if !at_rim_now && !was.iter().any(on_rim_in_mesh) {
                continue;
            }
            let same = live
                && now.iter().zip(&was).all(|(&l, &v)| {
                    (l as usize) < copied
                        && patch.sources[l as usize] == v
                        && copy.positions[l as usize] == self.positions[v as usize]
                });
            if !same {
                return Err(PutBackError::RimChanged { vertex: was[0] });
            }
        }
        Ok(())
    }

    /// For each copied vertex, whether a face around it in the mesh is not the patch's.
    fn rim_of(&self, patch: &Patch, in_patch: impl Fn(u32) -> bool) -> Vec<bool> {
        (patch.sources.iter())
            .map(|&v| self.faces_around(v).any(|f| !in_patch(f)))
            .collect()
    }

    /// Puts one patch back (its rim checked); returns its vertex map.
    fn put_back_one(
        &mut self,
        patch: &Patch,
        (in_patch, on_rim): (impl Fn(u32) -> bool, &[bool]),
    ) -> Vec<u32> {
        let copy = &patch.mesh;
        let vertex_map = self.put_back_vertices(patch, on_rim);
        // The copy's faces: its first ones take their slots back, the rest are appended.
        let mut face_map = patch.faces.clone();
        for f in patch.faces.len()..copy.face_count() {
            face_map.push(if copy.is_face_dead(f) {
                INVALID
            } else {
                self.faces.len() as u32
            });
            if !copy.is_face_dead(f) {
                self.faces.push([INVALID; 3]);
                self.face_layers.push(copy.face_layers[f]);
                self.adjacency.opposite.extend([INVALID; 3]);
            }
        }
        let corner = |c: u32| match face_map[face_of(c) as usize] {
            INVALID => INVALID,
            f => 3 * f + c % 3,
        };
        for (f, &slot) in face_map.iter().enumerate() {
            if slot == INVALID {
                continue;
            }
            let slot = slot as usize;
            self.faces[slot] = if copy.is_face_dead(f) {
                [INVALID; 3]
            } else {
                copy.faces[f].map(|v| vertex_map[v as usize])
            };
            for k in 0..3 {
                let was = self.adjacency.opposite[3 * slot + k];
                let across_rim = f < patch.faces.len() && was != INVALID && !in_patch(face_of(was));
                let o = copy.adjacency.opposite[3 * f + k];
                self.adjacency.opposite[3 * slot + k] = match () {
                    _ if copy.is_face_dead(f) => INVALID,
                    _ if o != INVALID => corner(o),
                    _ if across_rim => was,
                    _ => INVALID,
                };
            }
        }
        self.put_back_fans(patch, (&vertex_map, on_rim), corner);
        vertex_map
    }

    /// The copy's vertex data into the mesh: copied vertices in place, new ones appended. A
    /// rim vertex keeps its normal: the copy holds only part of its faces.
    fn put_back_vertices(&mut self, patch: &Patch, on_rim: &[bool]) -> Vec<u32> {
        let copy = &patch.mesh;
        let mut vertex_map = patch.sources.clone();
        for (i, &v) in patch.sources.iter().enumerate() {
            let v = v as usize;
            self.positions[v] = copy.positions[i];
            if !on_rim[i] {
                self.normals[v] = copy.normals[i];
            }
            self.brdfs[v] = copy.brdfs[i];
            self.flags[v] = copy.flags[i];
        }
        for i in patch.sources.len()..copy.vertex_count() {
            if copy.is_vertex_dead(i as u32) {
                vertex_map.push(INVALID);
                continue;
            }
            vertex_map.push(self.positions.len() as u32);
            self.positions.push(copy.positions[i]);
            self.normals.push(copy.normals[i]);
            self.brdfs.push(copy.brdfs[i]);
            self.vertex_layers.push(copy.vertex_layers[i]);
            self.flags.push(copy.flags[i]);
            self.adjacency.vertex_corner.push(INVALID);
        }
        vertex_map
    }

    /// Each vertex's corner: the copy's, except on the rim, where the fan goes on outside the
    /// copy and the mesh's corner (of a face that did not change) stays.
    fn put_back_fans(
        &mut self,
        patch: &Patch,
        (vertex_map, on_rim): (&[u32], &[bool]),
        corner: impl Fn(u32) -> u32,
    ) {
        let copy = &patch.mesh;
        for (i, &v) in vertex_map.iter().enumerate() {
            if v == INVALID {
                continue;
            }
            if on_rim.get(i) == Some(&true) {
                continue;
            }
            let c = copy.adjacency.vertex_corner[i];
            self.adjacency.vertex_corner[v as usize] =
                if c == INVALID || copy.is_vertex_dead(i as u32) {
                    INVALID
                } else {
                    corner(c)
                };
            if self.adjacency.vertex_corner[v as usize] == INVALID {
                self.flags[v as usize].insert(VertexFlags::DEAD);
            }
        }
    }
}
