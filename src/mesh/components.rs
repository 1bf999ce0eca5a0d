//! Connected components of the live faces (faces joined through shared vertices; on a manifold
//! mesh that is the same as through shared edges).

use super::{INVALID, LayerId, Mesh};

/// A component label per face and the layer of each component.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Components {
    /// Per face: its component, or `INVALID` for a dead face.
    pub face_component: Vec<u32>,
    /// Per component: its layer.
    pub layer: Vec<LayerId>,
    /// Per component: its number of faces.
    pub size: Vec<usize>,
}

impl Components {
    pub fn count(&self) -> usize {
        self.layer.len()
    }

    /// Number of components on each layer.
    pub fn per_layer(&self, layer_count: usize) -> Vec<usize> {
        let mut counts = vec![0; layer_count];
        for &l in &self.layer {
            counts[l as usize] += 1;
        }
        counts
    }
}

/// Union–find with path halving and union by size (components here, fans in `repair`).
pub(super) struct DisjointSets {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl DisjointSets {
    pub(super) fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    pub(super) fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let grandparent = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = grandparent;
            x = grandparent;
        }
        x
    }

    pub(super) fn union(&mut self, a: u32, b: u32) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.size[a as usize] < self.size[b as usize] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b as usize] = a;
        self.size[a as usize] += self.size[b as usize];
    }
}

impl Mesh {
    /// Labels the connected components, numbered in order of their first face.
    pub fn components(&self) -> Components {
        let mut sets = DisjointSets::new(self.vertex_count());
        for tri in self.faces().iter().filter(|t| t[0] != INVALID) {
            sets.union(tri[0], tri[1]);
            sets.union(tri[0], tri[2]);
        }
        let mut label_of_root = vec![INVALID; self.vertex_count()];
        let mut result = Components {
            face_component: vec![INVALID; self.face_count()],
            ..Components::default()
        };
        for (face, tri) in self.faces().iter().enumerate() {
            if tri[0] == INVALID {
                continue;
            }
            let root = sets.find(tri[0]) as usize;
            if label_of_root[root] == INVALID {
                label_of_root[root] = result.layer.len() as u32;
                result.layer.push(self.face_layers()[face]);
                result.size.push(0);
            }
            let label = label_of_root[root];
            result.face_component[face] = label;
            result.size[label as usize] += 1;
        }
        result
    }
}

/// A closed component (no boundary edge): its layer, face count, enclosed volume and the
/// centroid of its vertices (to match it with the same component in another version of the
/// mesh).
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedComponent {
    pub layer: LayerId,
    pub faces: usize,
    /// Signed: positive when the faces wind outward.
    pub volume: f64,
    pub centroid: glam::DVec3,
}

impl Mesh {
    /// Per component of `components` (this mesh's): whether it has a boundary edge.
    pub fn open_components(&self, components: &Components) -> Vec<bool> {
        let mut open = vec![false; components.count()];
        let opposite = &self.adjacency().opposite;
        for (face, &label) in components.face_component.iter().enumerate() {
            if label != INVALID && (0..3).any(|k| opposite[3 * face + k] == INVALID) {
                open[label as usize] = true;
            }
        }
        open
    }

    /// Every closed component, in order of their first face.
    pub fn closed_components(&self) -> Vec<ClosedComponent> {
        let components = self.components();
        let count = components.count();
        let open = self.open_components(&components);
        let mut sums = vec![(glam::DVec3::ZERO, 0usize); count];
        for (face, tri) in self.faces().iter().enumerate() {
            let label = components.face_component[face];
            if label == INVALID {
                continue;
            }
            for &v in tri {
                let s = &mut sums[label as usize];
                s.0 += self.positions()[v as usize].as_dvec3();
                s.1 += 1;
            }
        }
        let centroids: Vec<glam::DVec3> = sums.iter().map(|(s, n)| *s / *n as f64).collect();
        let mut volume = vec![0.0f64; count];
        for (face, tri) in self.faces().iter().enumerate() {
            let label = components.face_component[face];
            if label == INVALID || open[label as usize] {
                continue;
            }
            let o = centroids[label as usize];
            let [a, b, c] = tri.map(|v| self.positions()[v as usize].as_dvec3() - o);
            volume[label as usize] += a.dot(b.cross(c)) / 6.0;
        }
        (0..count)
            .filter(|&i| !open[i])
            .map(|i| ClosedComponent {
                layer: components.layer[i],
                faces: components.size[i],
                volume: volume[i],
                centroid: centroids[i],
            })
            .collect()
    }
}
