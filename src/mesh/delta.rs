//! What one edit changed in a mesh, row by row, so that it can be undone and redone bit for bit
//! without keeping copies of the mesh (the session's history, `session::History`).
//!
//! Every array of the mesh is compared with its state before the edit by its bytes (so `-0.0`
//! against `0.0`, or one NaN against another, count as changes), and only the rows that differ
//! are kept, with their values before and after, plus the rows the edit appended or removed at
//! the end. Topology is rows too: stroke remeshing kills faces in place and appends new ones (it
//! never compacts), so a split or collapse is a handful of changed face, corner and vertex rows.

use bytemuck::Pod;
use glam::Vec3;
use rayon::prelude::*;

use super::{Brdf, LayerId, Mesh, VertexFlags};
use crate::codec::{DecodeError, Reader, Writer};

/// Rows compared at once: equal blocks are skipped with one `memcmp`.
const BLOCK: usize = 1024;

/// The rows of one array an edit changed.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RowsDelta<T> {
    before_len: usize,
    after_len: usize,
    /// Rows below both lengths whose value changed, ascending.
    rows: Vec<u32>,
    /// Their values before, then the rows from the shorter length to `before_len`.
    before: Vec<T>,
    /// Their values after, then the rows from the shorter length to `after_len`.
    after: Vec<T>,
}

impl<T: Pod + Send + Sync> RowsDelta<T> {
    /// The difference from `old` to `new`.
    pub fn between(old: &[T], new: &[T]) -> RowsDelta<T> {
        let common = old.len().min(new.len());
        let rows: Vec<u32> = (0..common.div_ceil(BLOCK))
            .into_par_iter()
            .flat_map_iter(|block| {
                let range = block * BLOCK..((block + 1) * BLOCK).min(common);
                let same = bytes(&old[range.clone()]) == bytes(&new[range.clone()]);
                range
                    .filter(move |&i| {
                        !same && bytemuck::bytes_of(&old[i]) != bytemuck::bytes_of(&new[i])
                    })
                    .map(|i| i as u32)
            })
            .collect();
        let pick = |values: &[T]| -> Vec<T> {
            let mut picked: Vec<T> = rows.iter().map(|&i| values[i as usize]).collect();
            picked.extend_from_slice(&values[common..]);
            picked
        };
        RowsDelta {
            before_len: old.len(),
            after_len: new.len(),
            before: pick(old),
            after: pick(new),
            rows,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.rows.is_empty() && self.before_len == self.after_len
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.rows.len() * 4 + (self.before.len() + self.after.len()) * std::mem::size_of::<T>()
    }

    /// Puts the rows back as they were before the edit; `values` must be as the edit left them.
    fn undo(&self, values: &mut Vec<T>) {
        Self::restore(
            values,
            self.after_len,
            (&self.rows, &self.before),
            self.before_len,
        );
    }

    /// Makes the edit again; `values` must be as they were before it.
    fn redo(&self, values: &mut Vec<T>) {
        Self::restore(
            values,
            self.before_len,
            (&self.rows, &self.after),
            self.after_len,
        );
    }

    fn restore(values: &mut Vec<T>, from_len: usize, (rows, kept): (&[u32], &[T]), to_len: usize) {
        assert_eq!(
            values.len(),
            from_len,
            "a history entry applied to a mesh it was not recorded on"
        );
        let common = from_len.min(to_len);
        values.truncate(common);
        values.extend_from_slice(&kept[rows.len()..]);
        for (&row, &value) in rows.iter().zip(kept) {
            values[row as usize] = value;
        }
    }

    fn write(&self, out: &mut Writer) {
        out.u64(self.before_len as u64);
        out.u64(self.after_len as u64);
        out.array(&self.rows);
        out.array(&self.before);
        out.array(&self.after);
    }

    fn read(input: &mut Reader, what: &str) -> Result<RowsDelta<T>, DecodeError> {
        let before_len = input.u64(what)? as usize;
        let after_len = input.u64(what)? as usize;
        let rows: Vec<u32> = input.array(what)?;
        let before: Vec<T> = input.array(what)?;
        let after: Vec<T> = input.array(what)?;
        let common = before_len.min(after_len);
        let consistent = rows.windows(2).all(|w| w[0] < w[1])
            && rows.last().is_none_or(|&r| (r as usize) < common)
            && before.len() == rows.len() + (before_len - common)
            && after.len() == rows.len() + (after_len - common);
        if !consistent {
            return Err(DecodeError::new(what, "rows and values do not agree"));
        }
        Ok(RowsDelta {
            before_len,
            after_len,
            rows,
            before,
            after,
        })
    }
}

fn bytes<T: Pod>(values: &[T]) -> &[u8] {
    bytemuck::cast_slice(values)
}

/// Everything one edit changed in a [`Mesh`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshDelta {
    positions: RowsDelta<Vec3>,
    normals: RowsDelta<Vec3>,
    brdfs: RowsDelta<Brdf>,
    vertex_layers: RowsDelta<LayerId>,
    flags: RowsDelta<VertexFlags>,
    faces: RowsDelta<[u32; 3]>,
    face_layers: RowsDelta<LayerId>,
    opposite: RowsDelta<u32>,
    vertex_corner: RowsDelta<u32>,
    /// The layer names before and after, when they changed.
    layer_names: Option<(Vec<String>, Vec<String>)>,
}

impl MeshDelta {
    /// The difference from `old` to `new`.
    pub fn between(old: &Mesh, new: &Mesh) -> MeshDelta {
        let names = (old.layer_names != new.layer_names)
            .then(|| (old.layer_names.clone(), new.layer_names.clone()));
        MeshDelta {
            positions: RowsDelta::between(&old.positions, &new.positions),
            normals: RowsDelta::between(&old.normals, &new.normals),
            brdfs: RowsDelta::between(&old.brdfs, &new.brdfs),
            vertex_layers: RowsDelta::between(&old.vertex_layers, &new.vertex_layers),
            flags: RowsDelta::between(&old.flags, &new.flags),
            faces: RowsDelta::between(&old.faces, &new.faces),
            face_layers: RowsDelta::between(&old.face_layers, &new.face_layers),
            opposite: RowsDelta::between(&old.adjacency.opposite, &new.adjacency.opposite),
            vertex_corner: RowsDelta::between(
                &old.adjacency.vertex_corner,
                &new.adjacency.vertex_corner,
            ),
            layer_names: names,
        }
    }

    /// Nothing changed.
    pub fn is_empty(&self) -> bool {
        self.layer_names.is_none()
            && self.positions.is_empty()
            && self.normals.is_empty()
            && self.brdfs.is_empty()
            && self.vertex_layers.is_empty()
            && self.flags.is_empty()
            && self.topology_is_empty()
    }

    fn topology_is_empty(&self) -> bool {
        self.faces.is_empty()
            && self.face_layers.is_empty()
            && self.opposite.is_empty()
            && self.vertex_corner.is_empty()
    }

    /// Bytes held (what the history's memory cap counts).
    pub fn bytes(&self) -> usize {
        let names = self.layer_names.as_ref().map_or(0, |(a, b)| {
            a.iter().chain(b).map(|n| n.len() + 24).sum::<usize>()
        });
        self.positions.bytes()
            + self.normals.bytes()
            + self.brdfs.bytes()
            + self.vertex_layers.bytes()
            + self.flags.bytes()
            + self.faces.bytes()
            + self.face_layers.bytes()
            + self.opposite.bytes()
            + self.vertex_corner.bytes()
            + names
    }

    /// The vertices whose rows this delta touches (changed or appended/removed), ascending: what
    /// a viewer re-uploads after an undo or a redo.
    pub fn touched_vertices(&self) -> Vec<u32> {
        let mut touched: Vec<u32> = Vec::new();
        for delta in [&self.positions, &self.normals] {
            touched.extend(tail_and_rows(delta));
        }
        touched.extend(tail_and_rows(&self.brdfs));
        touched.extend(tail_and_rows(&self.flags));
        touched.sort_unstable();
        touched.dedup();
        touched
    }

    /// Undoes the edit on `mesh`, which must be as the edit left it.
    pub fn undo(&self, mesh: &mut Mesh) {
        self.apply(mesh, Direction::Undo);
    }

    /// Makes the edit again on `mesh`, which must be as it was before the edit.
    pub fn redo(&self, mesh: &mut Mesh) {
        self.apply(mesh, Direction::Redo);
    }

    fn apply(&self, mesh: &mut Mesh, direction: Direction) {
        fn go<T: Pod + Send + Sync>(d: &RowsDelta<T>, v: &mut Vec<T>, direction: Direction) {
            // An array the edit left alone (a layer-settings entry has no rows at all).
            if d.is_empty() {
                return;
            }
            match direction {
                Direction::Undo => d.undo(v),
                Direction::Redo => d.redo(v),
            }
        }
        go(&self.positions, &mut mesh.positions, direction);
        go(&self.normals, &mut mesh.normals, direction);
        go(&self.brdfs, &mut mesh.brdfs, direction);
        go(&self.vertex_layers, &mut mesh.vertex_layers, direction);
        go(&self.flags, &mut mesh.flags, direction);
        go(&self.faces, &mut mesh.faces, direction);
        go(&self.face_layers, &mut mesh.face_layers, direction);
        go(&self.opposite, &mut mesh.adjacency.opposite, direction);
        go(
            &self.vertex_corner,
            &mut mesh.adjacency.vertex_corner,
            direction,
        );
        if let Some((before, after)) = &self.layer_names {
            mesh.layer_names = match direction {
                Direction::Undo => before.clone(),
                Direction::Redo => after.clone(),
            };
        }
        // Counters move forward whichever way the content went: whoever keeps a copy of the
        // mesh (the pipeline's grid, the GPU's buffers) sees that it changed.
        let version = &mut mesh.version;
        if !self.topology_is_empty() || !self.vertex_layers.is_empty() {
            version.topology = super::next_stamp();
        }
        if !self.positions.is_empty() || !self.normals.is_empty() {
            version.positions = super::next_stamp();
        }
        if !self.brdfs.is_empty() || self.layer_names.is_some() {
            version.attributes = super::next_stamp();
        }
        if !self.flags.is_empty() {
            version.flags = super::next_stamp();
        }
    }

    /// Appends the delta's bytes (the session file's history section).
    pub fn write(&self, out: &mut Writer) {
        self.positions.write(out);
        self.normals.write(out);
        self.brdfs.write(out);
        self.vertex_layers.write(out);
        self.flags.write(out);
        self.faces.write(out);
        self.face_layers.write(out);
        self.opposite.write(out);
        self.vertex_corner.write(out);
        match &self.layer_names {
            None => out.u32(0),
            Some((before, after)) => {
                out.u32(1);
                out.strings(before);
                out.strings(after);
            }
        }
    }

    /// Reads what [`MeshDelta::write`] wrote. Whether it fits a mesh is checked when the
    /// history is read, by replaying it.
    pub fn read(input: &mut Reader) -> Result<MeshDelta, DecodeError> {
        let mut delta = MeshDelta {
            positions: RowsDelta::read(input, "positions")?,
            normals: RowsDelta::read(input, "normals")?,
            brdfs: RowsDelta::read(input, "brdfs")?,
            vertex_layers: RowsDelta::read(input, "vertex layers")?,
            flags: RowsDelta::read(input, "flags")?,
            faces: RowsDelta::read(input, "faces")?,
            face_layers: RowsDelta::read(input, "face layers")?,
            opposite: RowsDelta::read(input, "opposite corners")?,
            vertex_corner: RowsDelta::read(input, "vertex corners")?,
            layer_names: None,
        };
        delta.layer_names = match input.u32("layer names")? {
            0 => None,
            1 => Some((input.strings("layer names")?, input.strings("layer names")?)),
            other => {
                return Err(DecodeError::new(
                    "layer names",
                    format!("unknown marker {other}"),
                ));
            }
        };
        Ok(delta)
    }

    /// Whether the delta can be undone on `mesh`: every array it changes as long as the edit
    /// left it. Replaying a history read from a file checks this first, so a history that
    /// does not belong to its mesh is an error rather than a panic.
    pub fn fits_after(&self, mesh: &Mesh) -> bool {
        self.fits(mesh, |(_, after)| after)
            && self
                .layer_names
                .as_ref()
                .is_none_or(|(_, a)| *a == mesh.layer_names)
    }

    /// Whether the delta can be redone on `mesh`.
    pub fn fits_before(&self, mesh: &Mesh) -> bool {
        self.fits(mesh, |(before, _)| before)
            && self
                .layer_names
                .as_ref()
                .is_none_or(|(b, _)| *b == mesh.layer_names)
    }

    fn fits(&self, mesh: &Mesh, length: impl Fn((usize, usize)) -> usize) -> bool {
        self.lengths()
            .into_iter()
            .zip(mesh.array_lengths())
            .all(|(lengths, len)| lengths.is_none_or(|l| length(l) == len))
    }

    /// Each array's length before and after the edit, in [`Mesh::array_lengths`]'s order;
    /// `None` for an array the edit left as it was.
    pub fn lengths(&self) -> [Option<(usize, usize)>; 9] {
        fn of<T: Pod + Send + Sync>(d: &RowsDelta<T>) -> Option<(usize, usize)> {
            (!d.is_empty()).then_some((d.before_len, d.after_len))
        }
        [
            of(&self.positions),
            of(&self.normals),
            of(&self.brdfs),
            of(&self.vertex_layers),
            of(&self.flags),
            of(&self.faces),
            of(&self.face_layers),
            of(&self.opposite),
            of(&self.vertex_corner),
        ]
    }
}

impl Mesh {
    /// The length of each array a [`MeshDelta`] covers: positions, normals, BRDFs, vertex
    /// layers, flags, faces, face layers, opposite corners, vertex corners.
    pub fn array_lengths(&self) -> [usize; 9] {
        self.arrays_and_sizes().map(|(len, _)| len)
    }

    /// Bytes the mesh's arrays hold (what a history entry is measured against).
    pub fn memory_bytes(&self) -> usize {
        self.arrays_and_sizes()
            .iter()
            .map(|(len, size)| len * size)
            .sum()
    }

    /// Each array's length and the bytes of one of its rows.
    fn arrays_and_sizes(&self) -> [(usize, usize); 9] {
        fn of<T>(values: &[T]) -> (usize, usize) {
            (values.len(), std::mem::size_of::<T>())
        }
        [
            of(&self.positions),
            of(&self.normals),
            of(&self.brdfs),
            of(&self.vertex_layers),
            of(&self.flags),
            of(&self.faces),
            of(&self.face_layers),
            of(&self.adjacency.opposite),
            of(&self.adjacency.vertex_corner),
        ]
    }
}

/// The rows a delta changed, and those past the shorter of its two lengths.
fn tail_and_rows<T>(delta: &RowsDelta<T>) -> impl Iterator<Item = u32> + '_ {
    let common = delta.before_len.min(delta.after_len);
    let longer = delta.before_len.max(delta.after_len);
    delta
        .rows
        .iter()
        .copied()
        .chain((common..longer).map(|i| i as u32))
}

#[derive(Clone, Copy)]
enum Direction {
    Undo,
    Redo,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_round_trip_through_growth_and_shrinking() {
        let old = vec![1u32, 2, 3, 4, 5];
        for new in [
            vec![1, 9, 3],
            vec![1, 2, 3, 4, 5, 6, 7],
            vec![0, 2, 3, 4, 8],
            vec![],
        ] {
            let delta = RowsDelta::between(&old, &new);
            let mut values = new.clone();
            delta.undo(&mut values);
            assert_eq!(values, old);
            delta.redo(&mut values);
            assert_eq!(values, new);
        }
        assert!(RowsDelta::between(&old, &old).is_empty());
    }

    #[test]
    fn bits_not_values_are_compared() {
        let old = vec![0.0f32, f32::NAN];
        let new = vec![-0.0f32, f32::NAN];
        let delta = RowsDelta::between(&old, &new);
        assert_eq!(delta.rows, [0]);
        let mut values = new;
        delta.undo(&mut values);
        assert_eq!(values[0].to_bits(), 0.0f32.to_bits());
    }

    #[test]
    fn a_block_boundary_does_not_hide_a_change() {
        let old: Vec<u32> = (0..3 * BLOCK as u32 + 7).collect();
        let mut new = old.clone();
        for i in [0, BLOCK - 1, BLOCK, 2 * BLOCK + 3, old.len() - 1] {
            new[i] += 1;
        }
        let delta = RowsDelta::between(&old, &new);
        assert_eq!(delta.rows.len(), 5);
        let mut out = Writer::default();
        delta.write(&mut out);
        let read = RowsDelta::<u32>::read(&mut Reader::new(&out.bytes), "test").unwrap();
        assert_eq!(read, delta);
    }
}
