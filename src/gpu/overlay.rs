//! A small second hash table for the vertices remeshing changed, so that the main table need
//! not be rebuilt after every stroke. Rebuilding the main table is a pass over every vertex —
//! at 16M faces on lavapipe 2.2 s, most of a stroke — while remeshing changes a few thousand.
//! Those vertices (new ones among them) are filed in the overlay at their current positions and
//! marked; queries walk the main table leaving marked vertices out (their entries there are
//! stale, or missing for new vertices) and then the overlay. The overlay is built on the CPU
//! with the hash table's mirror (`crate::cpu::hash_table`) — a few thousand entries — and grows
//! stroke by stroke until the main table is rebuilt (drift, or the overlay passing
//! [`overlay_limit`]), which empties it.

use glam::Vec3;

use super::{CsrTable, table_size_for};

/// Vertices the overlay holds before the main table is rebuilt instead: a sixteenth of the
/// mesh. Filing is CPU work proportional to the overlay, at every refiling; a rebuild is GPU
/// work proportional to the mesh. Plaster on lavapipe, 40 strokes at 100K faces: selection
/// took 8.9–9.0 s with an overlay allowed to hold the whole mesh, 8.2–8.6 s with this limit
/// (37 rebuilds), 6.0–7.4 s rebuilding at every drift as before the overlay (small meshes
/// rebuild cheaply); at 16M faces a rebuild is 2.2 s and the overlay made a sample 16 times
/// cheaper.
pub fn overlay_limit(vertex_count: usize) -> usize {
    (vertex_count / 16).max(1024)
}

/// The table of `members` (vertex ids, ascending) at `positions`, in cells of
/// `1 / inv_cell_size`: entries are vertex ids, as in the main table.
pub fn overlay_table(positions: &[Vec3], members: &[u32], inv_cell_size: f32) -> CsrTable {
    let filed: Vec<Vec3> = members.iter().map(|&v| positions[v as usize]).collect();
    // Dead vertices stay filed: queries read the flags and leave them out.
    let alive = vec![0u32; members.len()];
    let mut table =
        crate::cpu::hash_table(&filed, &alive, inv_cell_size, table_size_for(members.len()));
    for entry in &mut table.entries {
        *entry = members[*entry as usize];
    }
    table
}

/// Where queries find each vertex when `members` are filed in the overlay at `positions` and
/// the others where the main table filed them (`hashed`).
pub struct Filing {
    /// Per vertex: the position it is filed at.
    pub filed_at: Vec<Vec3>,
    /// Per vertex: 1 for members.
    pub marks: Vec<u32>,
    /// How far any other vertex has moved since the main table filed it.
    pub drift: f32,
}

impl Filing {
    pub fn of(hashed: &[Vec3], positions: &[Vec3], members: &[u32]) -> Filing {
        let mut filed_at = hashed.to_vec();
        let mut marks = vec![0u32; positions.len()];
        for &v in members {
            filed_at[v as usize] = positions[v as usize];
            marks[v as usize] = 1;
        }
        let drift = (0..positions.len())
            .filter(|&v| marks[v] == 0)
            .map(|v| hashed[v].distance(positions[v]))
            .fold(0.0f32, f32::max);
        Filing {
            filed_at,
            marks,
            drift,
        }
    }
}

/// The buckets of a table a query walks (the main table's or the overlay's).
#[derive(Clone, Copy)]
pub struct TableBuffers<'a> {
    pub table_size: u32,
    pub offsets: &'a wgpu::Buffer,
    pub entries: &'a wgpu::Buffer,
}

/// The overlay as queries bind it, with the per-vertex marks of its members.
#[derive(Clone, Copy)]
pub struct OverlayBuffers<'a> {
    pub table: TableBuffers<'a>,
    /// Per vertex: nonzero for members.
    pub marks: &'a wgpu::Buffer,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlay_entries_are_vertex_ids_in_their_cells() {
        let positions: Vec<Vec3> = (0..50).map(|i| Vec3::splat(i as f32 * 0.3)).collect();
        let members = [3u32, 17, 18, 40];
        let table = overlay_table(&positions, &members, 1.0);
        let mut filed = table.entries.clone();
        filed.sort_unstable();
        assert_eq!(filed, members);
        for &v in &members {
            let cell = crate::grid::cell_coordinates(positions[v as usize], 1.0);
            let bucket = crate::grid::hash_cell(cell, table.table_size() as u32);
            assert!(
                table.bucket(bucket).contains(&v),
                "vertex {v} in its cell's bucket"
            );
        }
    }
}
