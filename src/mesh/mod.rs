//! One multi-layer triangle mesh (docs/design.md, "Data").
//!
//! Layers are labels on faces and vertices, not separate meshes: the sLayer paper applies every
//! operation "to individual vertices and triangles, with no special handling between different
//! layers". Vertices are struct-of-arrays so each attribute uploads to the GPU as one buffer;
//! adjacency is a corner table; deletion marks elements dead and [`Mesh::compact`] removes them.

mod assemble;
mod attributes;
mod components;
mod corner_table;
mod delta;
mod digest;
mod edit;
mod error;
mod extract;
mod genus;
mod measure;
mod patch;
mod raw;
mod repair;
mod ring;
mod slit;
mod stitch;
mod validate;
mod vertex_faces;

pub use attributes::{Brdf, LayerId, MIN_SLOPE, VertexFlags, blinn_exponent, partial_mask_factor};
pub use components::{ClosedComponent, Components};
pub use corner_table::{CornerTable, FanIter, INVALID, face_of, next, prev};
pub use delta::{MeshDelta, RowsDelta};
pub use error::MeshError;
pub use genus::ComponentShape;
pub use measure::EdgeLengthStats;
pub use patch::{Patch, PutBackError};
pub use raw::RawMeshError;
pub use repair::{Repaired, Repairs, Soup, repair, without_unreferenced};
pub use ring::{Ring, RingIter};
pub use vertex_faces::VertexFaces;

use glam::Vec3;

/// Coordinates beyond this magnitude are rejected: squared distances between such points would
/// overflow `f32`.
pub const MAX_COORDINATE: f32 = 1.0e18;

/// When each kind of data last changed, as a stamp ([`next_stamp`]): whoever keeps a copy of
/// the mesh (the pipeline's grid, the GPU backend's buffers) re-sends what moved on.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MeshVersion {
    /// Faces, adjacency or vertex count changed.
    pub topology: u64,
    /// Positions (and therefore normals) changed.
    pub positions: u64,
    /// BRDFs changed (painting, file import).
    pub attributes: u64,
    /// Vertex flags changed (masking). Apart from the BRDFs because the GPU keeps the flags
    /// and not the BRDFs: painting must not make it re-send them.
    pub flags: u64,
}

impl MeshVersion {
    /// A new mesh's version: stamps no other mesh has.
    fn fresh() -> MeshVersion {
        let stamp = next_stamp();
        MeshVersion {
            topology: stamp,
            positions: stamp,
            attributes: stamp,
            flags: stamp,
        }
    }

    /// One figure that grows with every kind of change.
    pub fn total(&self) -> u64 {
        self.topology + self.positions + self.attributes + self.flags
    }
}

/// Version stamps come from one counter for the whole process, so a change gives a value no
/// mesh had before: two meshes (a file opened in place of another, a clone edited apart from
/// its original) never show a copy-keeper the same version for different content.
fn next_stamp() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// Where each old element went after [`Mesh::compact`]: `INVALID` for removed ones.
#[derive(Debug, Clone, Default)]
pub struct Compaction {
    pub vertex_map: Vec<u32>,
    pub face_map: Vec<u32>,
}

/// A triangle mesh holding every layer of a material.
#[derive(Debug, Clone)]
pub struct Mesh {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    brdfs: Vec<Brdf>,
    vertex_layers: Vec<LayerId>,
    flags: Vec<VertexFlags>,
    faces: Vec<[u32; 3]>,
    face_layers: Vec<LayerId>,
    adjacency: CornerTable,
    layer_names: Vec<String>,
    version: MeshVersion,
}

impl Mesh {
    /// Builds a mesh from triangles. Every face names its layer; vertices take the layer of their
    /// faces (a vertex shared by two layers is an error: layers are separate surfaces). Unused
    /// vertices, repeated indices, non-manifold edges or vertices and flipped neighbours are errors
    /// naming the element. BRDFs start at [`Brdf::CLAY`], normals are computed.
    pub fn new(
        positions: Vec<Vec3>,
        faces: Vec<[u32; 3]>,
        face_layers: Vec<LayerId>,
        layer_names: Vec<String>,
    ) -> Result<Mesh, MeshError> {
        if face_layers.len() != faces.len() {
            return Err(MeshError::AttributeLength {
                attribute: "face_layers",
                len: face_layers.len(),
                expected: faces.len(),
            });
        }
        if positions.len() >= INVALID as usize {
            return Err(MeshError::TooLarge {
                what: "vertices",
                limit: INVALID as usize - 1,
            });
        }
        let vertex_count = positions.len();
        let mut vertex_layers = vec![INVALID; vertex_count];
        for (face, (tri, &layer)) in faces.iter().zip(&face_layers).enumerate() {
            if layer as usize >= layer_names.len() {
                return Err(MeshError::LayerOutOfRange {
                    face,
                    layer,
                    layer_count: layer_names.len(),
                });
            }
            for (corner, &v) in tri.iter().enumerate() {
                if v as usize >= vertex_count {
                    return Err(MeshError::IndexOutOfRange {
                        face,
                        corner: face * 3 + corner,
                        vertex: v,
                        vertex_count,
                    });
                }
                let slot = &mut vertex_layers[v as usize];
                if *slot == INVALID {
                    *slot = layer;
                } else if *slot != layer {
                    return Err(MeshError::LayerMismatch {
                        face,
                        vertex: v,
                        face_layer: layer,
                        vertex_layer: *slot,
                    });
                }
            }
            if tri[0] == tri[1] || tri[0] == tri[2] {
                return Err(MeshError::DegenerateFace {
                    face,
                    vertex: tri[0],
                });
            }
            if tri[1] == tri[2] {
                return Err(MeshError::DegenerateFace {
                    face,
                    vertex: tri[1],
                });
            }
        }
        if let Some(v) = vertex_layers.iter().position(|&l| l == INVALID) {
            return Err(MeshError::IsolatedVertex { vertex: v as u32 });
        }
        let adjacency = CornerTable::build(&faces, vertex_count)?;
        Ok(Mesh::from_checked(
            (positions, vertex_layers),
            (faces, face_layers),
            adjacency,
            layer_names,
        ))
    }

    /// A mesh from parts already checked as [`Mesh::new`] checks them, with their table:
    /// BRDFs [`Brdf::CLAY`], normals computed.
    fn from_checked(
        (positions, vertex_layers): (Vec<Vec3>, Vec<LayerId>),
        (faces, face_layers): (Vec<[u32; 3]>, Vec<LayerId>),
        adjacency: CornerTable,
        layer_names: Vec<String>,
    ) -> Mesh {
        let vertex_count = positions.len();
        let mut mesh = Mesh {
            normals: vec![Vec3::Z; vertex_count],
            brdfs: vec![Brdf::CLAY; vertex_count],
            flags: vec![VertexFlags::empty(); vertex_count],
            positions,
            vertex_layers,
            faces,
            face_layers,
            adjacency,
            layer_names,
            version: MeshVersion::fresh(),
        };
        mesh.recompute_normals();
        mesh.reserve_for_edits();
        mesh
    }

    // ---- sizes and plain data -------------------------------------------------------------

    /// Vertex slots, dead ones included.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Face slots, dead ones included.
    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    pub fn live_vertex_count(&self) -> usize {
        self.flags
            .iter()
            .filter(|f| !f.contains(VertexFlags::DEAD))
            .count()
    }

    pub fn live_face_count(&self) -> usize {
        self.faces.iter().filter(|f| f[0] != INVALID).count()
    }

    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Mutable positions; counts as a geometry change. Call [`recompute_normals`](Self::recompute_normals)
    /// or [`recompute_normals_at`](Self::recompute_normals_at) afterwards.
    pub fn positions_mut(&mut self) -> &mut [Vec3] {
        self.version.positions = next_stamp();
        &mut self.positions
    }

    /// Undoes a trial: puts each `(vertex, position)` back, the trial having moved only those
    /// vertices since the positions' version was `stamp`, and takes that version back, so that
    /// a copy current at `stamp` (the GPU's) is current again instead of sent anew.
    pub fn put_back_positions(&mut self, moved: impl IntoIterator<Item = (u32, Vec3)>, stamp: u64) {
        for (v, p) in moved {
            self.positions[v as usize] = p;
        }
        self.version.positions = stamp;
    }

    pub fn normals(&self) -> &[Vec3] {
        &self.normals
    }

    pub fn brdfs(&self) -> &[Brdf] {
        &self.brdfs
    }

    pub fn brdfs_mut(&mut self) -> &mut [Brdf] {
        self.version.attributes = next_stamp();
        &mut self.brdfs
    }

    pub fn vertex_layers(&self) -> &[LayerId] {
        &self.vertex_layers
    }

    pub fn flags(&self) -> &[VertexFlags] {
        &self.flags
    }

    pub fn flags_mut(&mut self) -> &mut [VertexFlags] {
        self.version.flags = next_stamp();
        &mut self.flags
    }

    /// Faces as vertex triples; a dead face is `[INVALID; 3]`.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    pub fn face_layers(&self) -> &[LayerId] {
        &self.face_layers
    }

    pub fn adjacency(&self) -> &CornerTable {
        &self.adjacency
    }

    pub fn layer_names(&self) -> &[String] {
        &self.layer_names
    }

    pub fn layer_count(&self) -> usize {
        self.layer_names.len()
    }

    pub fn version(&self) -> MeshVersion {
        self.version
    }

    /// Sets every vertex of `layer` to `brdf`.
    pub fn set_layer_brdf(&mut self, layer: LayerId, brdf: Brdf) {
        self.version.attributes = next_stamp();
        for (b, &l) in self.brdfs.iter_mut().zip(&self.vertex_layers) {
            if l == layer {
                *b = brdf;
            }
        }
    }

    /// Renames a layer; a `layer` past the last is ignored.
    pub fn set_layer_name(&mut self, layer: LayerId, name: &str) {
        if let Some(slot) = self.layer_names.get_mut(layer as usize) {
            *slot = name.to_string();
            self.version.attributes = next_stamp();
        }
    }

    /// Replaces all BRDFs at once (file import).
    pub fn set_brdfs(&mut self, brdfs: Vec<Brdf>) -> Result<(), MeshError> {
        if brdfs.len() != self.vertex_count() {
            return Err(MeshError::AttributeLength {
                attribute: "brdfs",
                len: brdfs.len(),
                expected: self.vertex_count(),
            });
        }
        self.version.attributes = next_stamp();
        // Copied into the array already there, which keeps the room made for edits.
        self.brdfs.clear();
        self.brdfs.extend_from_slice(&brdfs);
        Ok(())
    }

    // ---- navigation -----------------------------------------------------------------------

    #[inline]
    pub fn is_face_dead(&self, face: usize) -> bool {
        self.faces[face][0] == INVALID
    }

    #[inline]
    pub fn is_vertex_dead(&self, vertex: u32) -> bool {
        self.flags[vertex as usize].contains(VertexFlags::DEAD)
    }

    /// Not dead and on a face: what files write and the digest counts.
    pub fn is_vertex_live(&self, vertex: u32) -> bool {
        !self.is_vertex_dead(vertex) && self.adjacency.vertex_corner[vertex as usize] != INVALID
    }

    /// The vertex at a corner.
    #[inline]
    pub fn corner_vertex(&self, corner: u32) -> u32 {
        self.faces[corner as usize / 3][corner as usize % 3]
    }

    /// Faces around a vertex, in fan order.
    pub fn faces_around(&self, vertex: u32) -> impl Iterator<Item = u32> + '_ {
        self.adjacency.corners_around(vertex).map(face_of)
    }

    /// The one-ring of a vertex, in fan order. On a boundary it runs from one boundary
    /// neighbour to the other.
    pub fn neighbours(&self, vertex: u32) -> Ring {
        Ring::of(self, vertex)
    }

    /// [`Self::neighbours`] without gathering them.
    pub fn ring(&self, vertex: u32) -> impl Iterator<Item = u32> + '_ {
        // The first corner's other edge is the boundary edge the fan starts from.
        let first = self.adjacency.vertex_corner[vertex as usize];
        let boundary = self
            .is_boundary_vertex(vertex)
            .then(|| self.corner_vertex(prev(first)));
        let around = self.adjacency.corners_around(vertex);
        boundary
            .into_iter()
            .chain(around.map(|c| self.corner_vertex(next(c))))
    }

    /// True when the vertex lies on the boundary of an open sheet.
    pub fn is_boundary_vertex(&self, vertex: u32) -> bool {
        let c = self.adjacency.vertex_corner[vertex as usize];
        c != INVALID && self.adjacency.opposite[next(c) as usize] == INVALID
    }

    /// The CSR vertex→faces view that GPU kernels read.
    pub fn vertex_faces(&self) -> VertexFaces {
        VertexFaces::build(&self.faces, self.vertex_count())
    }

    /// Corners of the three vertices of a face, in order.
    pub fn face_positions(&self, face: usize) -> [Vec3; 3] {
        let [a, b, c] = self.faces[face];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    // ---- deletion and compaction ----------------------------------------------------------

    /// Marks a face dead and unlinks it from its neighbours. Vertices left without faces die
    /// too. The caller keeps the mesh manifold (a removal that leaves a vertex joining two fans
    /// makes `validate()` fail).
    pub fn kill_face(&mut self, face: usize) {
        if self.is_face_dead(face) {
            return;
        }
        let tri = self.faces[face];
        let fans: Vec<Vec<u32>> = tri
            .iter()
            .map(|&v| self.adjacency.corners_around(v).collect())
            .collect();
        for k in 0..3 {
            let c = (face * 3 + k) as u32;
            let o = self.adjacency.opposite[c as usize];
            if o != INVALID {
                self.adjacency.opposite[o as usize] = INVALID;
            }
            self.adjacency.opposite[c as usize] = INVALID;
        }
        self.faces[face] = [INVALID; 3];
        for (&v, fan) in tri.iter().zip(&fans) {
            let remaining = fan.iter().copied().filter(|&c| face_of(c) as usize != face);
            let mut choice = INVALID;
            for c in remaining {
                if self.adjacency.opposite[next(c) as usize] == INVALID {
                    choice = c;
                    break;
                }
                if choice == INVALID {
                    choice = c;
                }
            }
            self.adjacency.vertex_corner[v as usize] = choice;
            if choice == INVALID {
                self.flags[v as usize].insert(VertexFlags::DEAD);
            }
        }
        self.version.topology = next_stamp();
    }

    /// Removes dead faces and dead or unused vertices, keeping the order of the rest.
    pub fn compact(&mut self) -> Compaction {
        let mut used = vec![false; self.vertex_count()];
        for tri in self.faces.iter().filter(|t| t[0] != INVALID) {
            for &v in tri {
                used[v as usize] = true;
            }
        }
        let mut vertex_map = vec![INVALID; self.vertex_count()];
        let mut kept = 0u32;
        for (v, slot) in vertex_map.iter_mut().enumerate() {
            if used[v] && !self.flags[v].contains(VertexFlags::DEAD) {
                *slot = kept;
                kept += 1;
            }
        }
        let mut face_map = vec![INVALID; self.face_count()];
        let mut kept_faces = 0u32;
        for (f, slot) in face_map.iter_mut().enumerate() {
            if self.faces[f][0] != INVALID {
                *slot = kept_faces;
                kept_faces += 1;
            }
        }
        let remap_corner = |c: u32| {
            if c == INVALID {
                INVALID
            } else {
                face_map[c as usize / 3] * 3 + c % 3
            }
        };

        let keep_vertex = |v: usize| vertex_map[v] != INVALID;
        retain_indexed(&mut self.positions, keep_vertex);
        retain_indexed(&mut self.normals, keep_vertex);
        retain_indexed(&mut self.brdfs, keep_vertex);
        retain_indexed(&mut self.vertex_layers, keep_vertex);
        retain_indexed(&mut self.flags, keep_vertex);
        let mut vertex_corner = std::mem::take(&mut self.adjacency.vertex_corner);
        retain_indexed(&mut vertex_corner, keep_vertex);
        self.adjacency.vertex_corner = vertex_corner.into_iter().map(remap_corner).collect();

        let keep_face = |f: usize| face_map[f] != INVALID;
        retain_indexed(&mut self.faces, keep_face);
        retain_indexed(&mut self.face_layers, keep_face);
        for tri in &mut self.faces {
            for v in tri.iter_mut() {
                *v = vertex_map[*v as usize];
            }
        }
        let opposite = std::mem::take(&mut self.adjacency.opposite);
        self.adjacency.opposite = opposite
            .iter()
            .enumerate()
            .filter(|(c, _)| face_map[c / 3] != INVALID)
            .map(|(_, &o)| remap_corner(o))
            .collect();
        self.version.topology = next_stamp();
        Compaction {
            vertex_map,
            face_map,
        }
    }
}

/// Keeps the elements whose index passes `keep`, in order.
fn retain_indexed<T>(items: &mut Vec<T>, keep: impl Fn(usize) -> bool) {
    let mut index = 0;
    items.retain(|_| {
        let k = keep(index);
        index += 1;
        k
    });
}
