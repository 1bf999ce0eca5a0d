//! Corner-table adjacency (Rossignac's corner table): corner `c` is vertex `c % 3` of face `c / 3`;
//! `opposite[c]` is the corner facing `c` across the edge opposite `c`, or [`INVALID`] on a
//! boundary. With one corner per vertex this answers vertex–vertex, vertex–face and face–face
//! adjacency (what the sLayer paper keeps explicitly) in two flat `u32` arrays that upload to the
//! GPU as they are.

use rayon::prelude::*;

use super::MeshError;

/// Sentinel for "no element": a boundary corner's opposite, a dead face's vertices.
pub const INVALID: u32 = u32::MAX;

#[inline]
pub fn face_of(corner: u32) -> u32 {
    corner / 3
}

#[inline]
pub fn next(corner: u32) -> u32 {
    if corner % 3 == 2 {
        corner - 2
    } else {
        corner + 1
    }
}

#[inline]
pub fn prev(corner: u32) -> u32 {
    if corner.is_multiple_of(3) {
        corner + 2
    } else {
        corner - 1
    }
}

/// The two adjacency arrays of a triangle mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CornerTable {
    /// Per corner: the corner across the opposite edge, or `INVALID` on a boundary.
    pub opposite: Vec<u32>,
    /// Per vertex: one of its corners. For a boundary vertex it is the first corner of its fan
    /// when turning with [`swing_right`](CornerTable::swing_right), so one walk visits the whole fan.
    pub vertex_corner: Vec<u32>,
}

impl CornerTable {
    /// Next corner around the same vertex, across the edge from that vertex to `next(corner)`'s
    /// vertex; `INVALID` when that edge is a boundary.
    #[inline]
    pub fn swing_right(&self, corner: u32) -> u32 {
        let o = self.opposite[prev(corner) as usize];
        if o == INVALID { INVALID } else { prev(o) }
    }

    /// Previous corner around the same vertex (inverse of [`swing_right`](Self::swing_right)).
    #[inline]
    pub fn swing_left(&self, corner: u32) -> u32 {
        let o = self.opposite[next(corner) as usize];
        if o == INVALID { INVALID } else { next(o) }
    }

    /// Builds the table for `faces` (dead faces are rows of `INVALID`), or names the first
    /// non-manifold or inconsistently oriented element.
    pub fn build(faces: &[[u32; 3]], vertex_count: usize) -> Result<Self, MeshError> {
        let corner_count = faces.len() * 3;
        if corner_count >= INVALID as usize {
            return Err(MeshError::TooLarge {
                what: "corners",
                limit: INVALID as usize - 1,
            });
        }
        let vertex = |c: u32| faces[c as usize / 3][c as usize % 3];

        // Each corner names the edge opposite it, directed next → prev. Corners are filed by
        // the lower vertex of that edge (a counting sort: 4 bytes a corner, where sorting
        // (key, corner) pairs took 16, the largest allocation of loading a big mesh), then
        // within each vertex's few by the higher one, which groups the (at most two) corners
        // that face each other. Vertices are taken in order, so the first bad edge reported
        // is the one with the smallest key.
        let ends = |c: u32| {
            let (a, b) = (vertex(next(c)), vertex(prev(c)));
            (a.min(b), a.max(b))
        };
        let mut offsets = vec![0u32; vertex_count + 1];
        for c in (0..corner_count as u32).filter(|&c| vertex(c) != INVALID) {
            offsets[ends(c).0 as usize + 1] += 1;
        }
        for v in 0..vertex_count {
            offsets[v + 1] += offsets[v];
        }
        let mut filed = vec![INVALID; offsets[vertex_count] as usize];
        let mut cursor = offsets.clone();
        for c in (0..corner_count as u32).filter(|&c| vertex(c) != INVALID) {
            let low = ends(c).0 as usize;
            filed[cursor[low] as usize] = c;
            cursor[low] += 1;
        }
        drop(cursor);

        let mut opposite = vec![INVALID; corner_count];
        for v in 0..vertex_count {
            let bucket = &mut filed[offsets[v] as usize..offsets[v + 1] as usize];
            bucket.sort_unstable_by_key(|&c| (ends(c).1, c));
            let mut start = 0;
            while start < bucket.len() {
                let high = ends(bucket[start]).1;
                let mut end = start + 1;
                while end < bucket.len() && ends(bucket[end]).1 == high {
                    end += 1;
                }
                match end - start {
                    1 => {}
                    2 => {
                        let (c0, c1) = (bucket[start], bucket[start + 1]);
                        if vertex(next(c0)) == vertex(next(c1)) {
                            return Err(MeshError::InconsistentOrientation {
                                a: vertex(next(c0)),
                                b: vertex(prev(c0)),
                                face_a: face_of(c0) as usize,
                                face_b: face_of(c1) as usize,
                            });
                        }
                        opposite[c0 as usize] = c1;
                        opposite[c1 as usize] = c0;
                    }
                    n => {
                        return Err(MeshError::NonManifoldEdge {
                            a: v as u32,
                            b: high,
                            faces: n,
                        });
                    }
                }
                start = end;
            }
        }
        drop(filed);

        let mut table = CornerTable {
            opposite,
            vertex_corner: vec![INVALID; vertex_count],
        };
        table.assign_vertex_corners(faces)?;
        Ok(table)
    }

    /// The table of some of this table's faces, renumbered: `kept[f]` is the new index of
    /// face `f` (or `INVALID`), `faces` the kept faces' new vertices, corner for corner. Opposite
    /// corners carry over where both faces are kept (a manifold table has one answer, so this is
    /// the table [`CornerTable::build`] would make); each vertex's fan is then checked as it
    /// does, since dropping faces can leave two fans at one vertex.
    pub fn restricted(
        &self,
        kept: &[u32],
        faces: &[[u32; 3]],
        vertex_count: usize,
    ) -> Result<Self, MeshError> {
        let mut opposite = vec![INVALID; faces.len() * 3];
        for (old, &new) in kept.iter().enumerate().filter(|(_, new)| **new != INVALID) {
            for k in 0..3 {
                let o = self.opposite[3 * old + k];
                if o != INVALID && kept[face_of(o) as usize] != INVALID {
                    opposite[3 * new as usize + k] = 3 * kept[face_of(o) as usize] + o % 3;
                }
            }
        }
        let mut table = CornerTable {
            opposite,
            vertex_corner: vec![INVALID; vertex_count],
        };
        table.assign_vertex_corners(faces)?;
        Ok(table)
    }

    /// Picks each vertex's corner (the start of its fan on a boundary) and checks that every
    /// vertex has exactly one fan.
    fn assign_vertex_corners(&mut self, faces: &[[u32; 3]]) -> Result<(), MeshError> {
        let vertex = |c: u32| faces[c as usize / 3][c as usize % 3];
        let mut incidence = vec![0u32; self.vertex_corner.len()];
        for c in 0..(faces.len() * 3) as u32 {
            let v = vertex(c);
            if v == INVALID {
                continue;
            }
            incidence[v as usize] += 1;
            let starts_fan = self.opposite[next(c) as usize] == INVALID;
            let slot = &mut self.vertex_corner[v as usize];
            if starts_fan {
                if *slot != INVALID && self.opposite[next(*slot) as usize] == INVALID {
                    return Err(MeshError::NonManifoldVertex { vertex: v });
                }
                *slot = c;
            } else if *slot == INVALID {
                *slot = c;
            }
        }
        // Every corner of a manifold vertex is reached by one walk around it.
        let table = &*self;
        let bad = (0..table.vertex_corner.len())
            .into_par_iter()
            .find_first(|&v| {
                let start = table.vertex_corner[v];
                start != INVALID && table.fan_len(start) != incidence[v]
            });
        if let Some(v) = bad {
            return Err(MeshError::NonManifoldVertex { vertex: v as u32 });
        }
        Ok(())
    }

    /// Number of corners met walking right from `start` until a boundary or back to `start`.
    pub fn fan_len(&self, start: u32) -> u32 {
        let mut count = 0;
        let mut c = start;
        loop {
            count += 1;
            c = self.swing_right(c);
            if c == INVALID || c == start || count >= MAX_FAN {
                return count;
            }
        }
    }

    /// The corners around a vertex, starting at its stored corner.
    pub fn corners_around(&self, vertex: u32) -> FanIter<'_> {
        let start = self.vertex_corner[vertex as usize];
        FanIter {
            table: self,
            start,
            current: start,
            remaining: MAX_FAN,
        }
    }
}

/// Iterator over the corners of one vertex's fan.
pub struct FanIter<'a> {
    table: &'a CornerTable,
    start: u32,
    current: u32,
    /// A fan never has more corners than this; a corrupted table cannot loop forever.
    remaining: u32,
}

/// Most corners a fan walk visits (a valence far beyond any real mesh).
pub const MAX_FAN: u32 = 1 << 16;

impl Iterator for FanIter<'_> {
    type Item = u32;

    fn next(&mut self) -> Option<u32> {
        if self.current == INVALID || self.remaining == 0 {
            return None;
        }
        self.remaining -= 1;
        let c = self.current;
        let n = self.table.swing_right(c);
        self.current = if n == self.start { INVALID } else { n };
        Some(c)
    }
}
