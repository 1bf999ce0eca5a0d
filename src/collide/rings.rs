//! Exclusion rings kept from step to step. A ring depends on the topology alone, and a grab
//! moves the same vertices at every step of its stroke: finding rings (up to 4 deep, ~60
//! vertices, walked through the corner table) was a quarter of a long grab's time, half of it
//! the collision phase finding the same rings again at every step. Each is now found once while
//! the topology stands.

use rayon::prelude::*;

use super::neighbourhood::ring_vertices;
use crate::mesh::{INVALID, Mesh};

/// The most ring entries kept (64 MiB): past it the cache starts over, so a stroke over a huge
/// selection keeps a bounded amount.
const MAX_ENTRIES: usize = 1 << 24;

/// Sorted exclusion rings of vertices, valid for one topology and one ring width.
#[derive(Debug, Default)]
pub struct RingCache {
    /// The mesh topology stamp and the ring width the rings were found for.
    topology: u64,
    ring: u32,
    /// Per vertex: where its ring starts in `lists` (its length first), or `INVALID`.
    start: Vec<u32>,
    lists: Vec<u32>,
    /// The vertices that have an entry in `start`, to empty it without a sweep.
    cached: Vec<u32>,
}

impl RingCache {
    /// Finds the rings of `vertices` that are not kept yet (in parallel when `parallel`),
    /// first forgetting everything if the topology or the width changed.
    pub fn prepare(&mut self, mesh: &Mesh, ring: u32, vertices: &[u32], parallel: bool) {
        let topology = mesh.version().topology;
        if topology != self.topology || ring != self.ring || self.lists.len() > MAX_ENTRIES {
            self.forget();
            (self.topology, self.ring) = (topology, ring);
        }
        let missing: Vec<u32> = vertices
            .iter()
            .copied()
            .filter(|&v| self.start.get(v as usize).is_none_or(|&s| s == INVALID))
            .collect();
        // Sized for the mesh at set-up (`size_for`); here only for vertices made since.
        if let Some(&highest) = missing.iter().max() {
            crate::grow::grow_to(&mut self.start, highest as usize + 1, INVALID);
        }
        let find = |scratch: &mut Vec<u32>, v: u32| {
            ring_vertices(mesh, v, ring, scratch);
            scratch.clone()
        };
        let rings: Vec<Vec<u32>> = if parallel {
            missing
                .par_iter()
                .map_init(Vec::new, |s, &v| find(s, v))
                .collect()
        } else {
            let mut scratch = Vec::new();
            missing.iter().map(|&v| find(&mut scratch, v)).collect()
        };
        for (v, found) in missing.into_iter().zip(rings) {
            self.start[v as usize] = self.lists.len() as u32;
            self.lists.push(found.len() as u32);
            self.lists.extend(found);
            self.cached.push(v);
        }
    }

    /// The ring of `v` as [`ring_vertices`] finds it, if kept for `mesh`'s topology and width
    /// `ring`.
    pub fn get(&self, mesh: &Mesh, v: u32, ring: u32) -> Option<&[u32]> {
        if mesh.version().topology != self.topology || ring != self.ring {
            return None;
        }
        let start = *self.start.get(v as usize)? as usize;
        if start == INVALID as usize {
            return None;
        }
        let len = self.lists[start] as usize;
        Some(&self.lists[start + 1..start + 1 + len])
    }

    /// Makes room for the rings of `vertex_count` vertices ahead of the first step (set-up):
    /// filling the per-vertex array up to the highest vertex a stroke meets cost its first
    /// stroke on a 16M-face mesh about 190 ms, a pass over the whole array.
    pub fn size_for(&mut self, vertex_count: usize) {
        crate::grow::grow_to(&mut self.start, vertex_count, INVALID);
    }

    fn forget(&mut self) {
        for v in self.cached.drain(..) {
            self.start[v as usize] = INVALID;
        }
        self.lists.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes::stacked_sheets;

    #[test]
    fn kept_rings_are_the_rings_and_are_forgotten_when_the_topology_changes() {
        let mut mesh = stacked_sheets(1, 6, 6, 1.0, 1.0);
        let mut cache = RingCache::default();
        let vertices: Vec<u32> = (0..mesh.vertex_count() as u32).collect();
        cache.prepare(&mesh, 2, &vertices, true);
        let mut expected = Vec::new();
        for &v in &vertices {
            ring_vertices(&mesh, v, 2, &mut expected);
            assert_eq!(cache.get(&mesh, v, 2), Some(&expected[..]), "vertex {v}");
        }
        assert_eq!(cache.get(&mesh, 0, 3), None, "another width");
        let corner = (0..mesh.faces().len() as u32 * 3)
            .find(|&c| mesh.is_flip_ok(c))
            .unwrap();
        mesh.flip_edge(corner);
        assert_eq!(cache.get(&mesh, 0, 2), None, "another topology");
        cache.prepare(&mesh, 2, &[0], false);
        ring_vertices(&mesh, 0, 2, &mut expected);
        assert_eq!(cache.get(&mesh, 0, 2), Some(&expected[..]));
        assert_eq!(cache.get(&mesh, 1, 2), None, "forgotten");
    }
}
