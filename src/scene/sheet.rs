//! Layered sheets on a triangular lattice: each layer is the part of an equilateral lattice that
//! its mask keeps, lifted by its height field. Equilateral triangles and gentle height fields give
//! near-uniform edges; masks cut holes and disconnected patches.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::mesh::{Brdf, LayerId, Mesh, MeshError, VertexFaces};

/// One layer of a sheet scene. Heights and masks are functions of the lattice point `(x, y)`.
pub struct SheetLayer<'a> {
    pub name: String,
    pub brdf: Brdf,
    /// Height above the plane z = 0.
    pub height: Box<dyn Fn(Vec2) -> f32 + Sync + 'a>,
    /// Which faces to keep, tested at each face's centroid.
    pub keep: Box<dyn Fn(Vec2) -> bool + Sync + 'a>,
}

/// A rectangular equilateral lattice of `columns × rows` points with spacing `edge`.
#[derive(Debug, Clone, Copy)]
pub struct Lattice {
    pub origin: Vec2,
    pub edge: f32,
    pub columns: u32,
    pub rows: u32,
}

impl Lattice {
    /// The lattice covering `size` with edge length `edge`.
    pub fn covering(size: Vec2, edge: f32) -> Lattice {
        let row_height = edge * 3f32.sqrt() / 2.0;
        Lattice {
            origin: Vec2::ZERO,
            edge,
            columns: ((size.x / edge).floor() as u32).max(1) + 1,
            rows: ((size.y / row_height).floor() as u32).max(1) + 1,
        }
    }

    pub fn point_count(&self) -> usize {
        self.columns as usize * self.rows as usize
    }

    pub fn face_count(&self) -> usize {
        2 * (self.columns as usize - 1) * (self.rows as usize - 1)
    }

    /// Position of lattice point `(i, j)`; odd rows are shifted by half an edge.
    pub fn point(&self, i: u32, j: u32) -> Vec2 {
        let shift = if j % 2 == 1 { 0.5 } else { 0.0 };
        self.origin
            + Vec2::new(
                (i as f32 + shift) * self.edge,
                j as f32 * self.edge * 3f32.sqrt() / 2.0,
            )
    }

    fn index(&self, i: u32, j: u32) -> u32 {
        j * self.columns + i
    }

    /// Face `k` as lattice point indices, counter-clockwise seen from +z.
    pub fn face(&self, k: usize) -> [u32; 3] {
        let quad = k / 2;
        let (i, j) = (
            (quad % (self.columns as usize - 1)) as u32,
            (quad / (self.columns as usize - 1)) as u32,
        );
        let at = |di: u32, dj: u32| self.index(i + di, j + dj);
        match (j % 2 == 0, k.is_multiple_of(2)) {
            (true, true) => [at(0, 0), at(1, 0), at(0, 1)],
            (true, false) => [at(1, 0), at(1, 1), at(0, 1)],
            (false, true) => [at(0, 0), at(1, 1), at(0, 1)],
            (false, false) => [at(0, 0), at(1, 0), at(1, 1)],
        }
    }

    fn point_of_index(&self, index: u32) -> Vec2 {
        self.point(index % self.columns, index / self.columns)
    }

    fn centroid(&self, face: [u32; 3]) -> Vec2 {
        face.iter().map(|&p| self.point_of_index(p)).sum::<Vec2>() / 3.0
    }
}

/// Number of faces the masks keep at a given lattice (before cleanup), for sizing.
pub fn kept_face_count(lattice: &Lattice, masks: &[&(dyn Fn(Vec2) -> bool + Sync)]) -> usize {
    (0..lattice.face_count())
        .into_par_iter()
        .map(|k| {
            let c = lattice.centroid(lattice.face(k));
            masks.iter().filter(|keep| keep(c)).count()
        })
        .sum()
}

/// The lattice faces each layer keeps: those its mask keeps, cleaned so that every vertex has
/// one fan (no bow-ties) and without patches smaller than `min_patch_faces`.
pub fn kept_faces(
    lattice: &Lattice,
    layers: &[SheetLayer<'_>],
    min_patch_faces: usize,
) -> Vec<Vec<[u32; 3]>> {
    layers
        .iter()
        .map(|layer| {
            let mut kept: Vec<[u32; 3]> = (0..lattice.face_count())
                .into_par_iter()
                .map(|k| lattice.face(k))
                .filter(|&f| (layer.keep)(lattice.centroid(f)))
                .collect();
            remove_bowties(&mut kept, lattice.point_count());
            drop_small_patches(&mut kept, lattice.point_count(), min_patch_faces);
            kept
        })
        .collect()
}

/// Builds the mesh of all layers on one lattice from the faces [`kept_faces`] chose.
pub fn build_sheets(
    lattice: &Lattice,
    layers: &[SheetLayer<'_>],
    kept: &[Vec<[u32; 3]>],
) -> Result<Mesh, MeshError> {
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    let mut face_layers = Vec::new();
    let mut brdfs = Vec::new();
    for (layer_index, (layer, kept)) in layers.iter().zip(kept).enumerate() {
        // Number the used lattice points in lattice order, so output is independent of threads.
        let mut new_index = vec![u32::MAX; lattice.point_count()];
        for f in kept {
            for &p in f {
                new_index[p as usize] = 0;
            }
        }
        let base = positions.len() as u32;
        let used: Vec<u32> = (0..lattice.point_count() as u32)
            .filter(|&p| new_index[p as usize] == 0)
            .collect();
        for (n, &p) in used.iter().enumerate() {
            new_index[p as usize] = base + n as u32;
        }
        let lifted: Vec<Vec3> = used
            .par_iter()
            .map(|&p| {
                let xy = lattice.point_of_index(p);
                xy.extend((layer.height)(xy))
            })
            .collect();
        positions.extend(lifted);
        brdfs.extend(std::iter::repeat_n(layer.brdf, used.len()));
        faces.extend(kept.iter().map(|f| f.map(|p| new_index[p as usize])));
        face_layers.extend(std::iter::repeat_n(layer_index as LayerId, kept.len()));
    }
    let names = layers.iter().map(|l| l.name.clone()).collect();
    let mut mesh = Mesh::new(positions, faces, face_layers, names)?;
    mesh.set_brdfs(brdfs)?;
    Ok(mesh)
}

/// Removes faces so that each lattice point's kept faces form one edge-connected fan; the
/// largest fan stays. Repeats until stable (a removal can split a neighbour's fan).
fn remove_bowties(faces: &mut Vec<[u32; 3]>, point_count: usize) {
    loop {
        let incident = VertexFaces::build(faces, point_count);
        let mut doomed = vec![false; faces.len()];
        for p in 0..point_count {
            let around = incident.of(p as u32);
            if around.len() < 2 {
                continue;
            }
            // Group the faces around p by shared edges (a shared second vertex).
            let mut group: Vec<usize> = (0..around.len()).collect();
            fn root(group: &mut [usize], mut x: usize) -> usize {
                while group[x] != x {
                    x = group[x];
                }
                x
            }
            for a in 0..around.len() {
                for b in a + 1..around.len() {
                    let fa = faces[around[a] as usize];
                    let fb = faces[around[b] as usize];
                    let shared = fa.iter().filter(|v| fb.contains(v)).count();
                    if shared >= 2 {
                        let (ra, rb) = (root(&mut group, a), root(&mut group, b));
                        group[ra.max(rb)] = ra.min(rb);
                    }
                }
            }
            let roots: Vec<usize> = (0..around.len()).map(|a| root(&mut group, a)).collect();
            let mut sizes = vec![0usize; around.len()];
            for &r in &roots {
                sizes[r] += 1;
            }
            let keep = (0..around.len())
                .max_by_key(|&r| (sizes[r], usize::MAX - r))
                .unwrap_or(0);
            for (a, &r) in roots.iter().enumerate() {
                if r != keep {
                    doomed[around[a] as usize] = true;
                }
            }
        }
        if !doomed.contains(&true) {
            return;
        }
        let mut index = 0;
        faces.retain(|_| {
            index += 1;
            !doomed[index - 1]
        });
    }
}

/// Drops edge-connected patches with fewer than `min_faces` faces.
fn drop_small_patches(faces: &mut Vec<[u32; 3]>, point_count: usize, min_faces: usize) {
    if faces.is_empty() || min_faces <= 1 {
        return;
    }
    let mut parent: Vec<u32> = (0..point_count as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for f in faces.iter() {
        for k in 1..3 {
            let (a, b) = (find(&mut parent, f[0]), find(&mut parent, f[k]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut size = vec![0usize; point_count];
    let roots: Vec<u32> = faces.iter().map(|f| find(&mut parent, f[0])).collect();
    for &r in &roots {
        size[r as usize] += 1;
    }
    let mut index = 0;
    faces.retain(|_| {
        index += 1;
        size[roots[index - 1] as usize] >= min_faces
    });
}
