//! Variable-length per-vertex rows (a vertex's faces, its smoothing neighbours) laid out so that
//! remeshing can rewrite a few rows without moving the others. A plain CSR array — starts, then
//! the rows back to back — shifts every later start when one row grows, so the first GPU
//! backend re-sent all of it after every stroke (at 16M faces, most of a stroke's time on
//! lavapipe). Here each row has a table entry (start, length) and a slot of its own with one
//! word of room; a row rewritten within its slot stays where it is, one that outgrows it moves
//! to the end of the words, and a new vertex's row is placed there too. When the words run out,
//! the owner lays everything out afresh with [`SlottedRows::build`].
//!
//! Kernels read row `r` as `table[2r]` (absolute start) and `table[2r + 1]` (length).

use super::reusable::Patches;

/// Words of room each row gets beyond its length: remeshing edits change a vertex's valence by
/// one at a time.
const ROW_ROOM: u32 = 1;

/// Where each row lives; the words themselves are on the GPU.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SlottedRows {
    /// Per row: absolute start (`base` included), length.
    pub table: Vec<u32>,
    /// Per row: the words its slot holds.
    slot: Vec<u32>,
    /// Where the rows' words start in their buffer (the words before belong to others).
    base: u32,
    /// Words laid out so far (relative to `base`), and the words there is room for.
    used: u32,
    capacity: u32,
}

impl SlottedRows {
    /// Lays out `rows` (row `r` is `rows(r)`, for `count` rows) from word `base` on, with room
    /// for `spare_rows` more rows and a quarter more words than they fill now. Returns the
    /// layout and the words, `capacity` of them (spare ones zero).
    pub fn build(
        count: usize,
        spare_rows: usize,
        base: u32,
        mut rows: impl FnMut(u32, &mut Vec<u32>),
    ) -> (SlottedRows, Vec<u32>) {
        let mut words = Vec::new();
        let mut table = Vec::with_capacity(2 * (count + spare_rows));
        let mut slot = Vec::with_capacity(count + spare_rows);
        let mut row = Vec::new();
        for r in 0..count as u32 {
            row.clear();
            rows(r, &mut row);
            table.extend([base + words.len() as u32, row.len() as u32]);
            slot.push(row.len() as u32 + ROW_ROOM);
            words.extend_from_slice(&row);
            words.extend(std::iter::repeat_n(0, ROW_ROOM as usize));
        }
        let used = words.len() as u32;
        // Room for the rows that grow past their slots and for new vertices' rows.
        let mean_row = (used as usize).div_ceil(count.max(1)).max(1);
        let capacity = used as usize + used as usize / 4 + spare_rows * mean_row + 64;
        words.resize(capacity, 0);
        (
            SlottedRows {
                table,
                slot,
                base,
                used,
                capacity: capacity as u32,
            },
            words,
        )
    }

    pub fn row_count(&self) -> usize {
        self.slot.len()
    }

    /// The words there is room for, from `base` on.
    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// Sets row `r` (which may be one past the last, a new row) to `len` words: in its slot if
    /// they fit, else in a new slot at the end. Returns the row's absolute start; `None` when
    /// the words have run out (lay the rows out afresh).
    pub fn place(&mut self, r: u32, len: u32) -> Option<u32> {
        let r = r as usize;
        if r == self.slot.len() {
            self.table.extend([0, 0]);
            self.slot.push(0);
        }
        assert!(
            r < self.slot.len(),
            "rows are added one at a time, in order"
        );
        if len > self.slot[r] {
            let room = len + ROW_ROOM;
            if self.used + room > self.capacity {
                return None;
            }
            self.table[2 * r] = self.base + self.used;
            self.slot[r] = room;
            self.used += room;
        }
        self.table[2 * r + 1] = len;
        Some(self.table[2 * r])
    }

    /// Rewrites the rows of `changed` (ascending; new rows among them) with `row_of` into
    /// `patches`: each row's words into `words`, its (start, length) entry into `table` from
    /// word `table_base` on. `false` when the words have run out (lay the rows out afresh).
    pub fn patch<'a>(
        &mut self,
        changed: &[u32],
        mut row_of: impl FnMut(u32, &mut Vec<u32>),
        ((table, table_base), words): ((&'a wgpu::Buffer, usize), &'a wgpu::Buffer),
        patches: &mut Patches<'a>,
    ) -> bool {
        let mut row = Vec::new();
        for &v in changed {
            row.clear();
            row_of(v, &mut row);
            let Some(start) = self.place(v, row.len() as u32) else {
                return false;
            };
            patches.write(words, start as usize, &row);
            let entry = table_base + 2 * v as usize;
            patches.write(table, entry, &[start, row.len() as u32]);
        }
        true
    }

    /// Start and length of row `r`.
    pub fn row(&self, r: u32) -> (u32, u32) {
        (self.table[2 * r as usize], self.table[2 * r as usize + 1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows_of(lists: &[Vec<u32>]) -> impl FnMut(u32, &mut Vec<u32>) + '_ {
        |r, out| out.extend_from_slice(&lists[r as usize])
    }

    fn read(layout: &SlottedRows, words: &[u32], r: u32) -> Vec<u32> {
        let (start, len) = layout.row(r);
        words[start as usize..(start + len) as usize].to_vec()
    }

    #[test]
    fn rows_are_read_back_through_the_table() {
        let lists = vec![vec![1, 2, 3], vec![], vec![7]];
        let (layout, mut words) = SlottedRows::build(3, 0, 10, rows_of(&lists));
        let mut buffer = vec![0; 10];
        buffer.append(&mut words);
        for (r, list) in lists.iter().enumerate() {
            assert_eq!(&read(&layout, &buffer, r as u32), list);
        }
    }

    #[test]
    fn a_row_stays_in_its_slot_until_it_outgrows_it() {
        let lists = vec![vec![1, 2], vec![3, 4, 5]];
        let (mut layout, _) = SlottedRows::build(2, 1, 0, rows_of(&lists));
        let start = layout.row(0).0;
        // One word of room: three words still fit.
        assert_eq!(layout.place(0, 3), Some(start));
        let moved = layout.place(0, 4).expect("room at the end");
        assert_ne!(moved, start);
        assert!(moved >= layout.row(1).0 + 3, "past every other row");
        // A new row goes to the end too.
        let new = layout.place(2, 5).expect("room for a new row");
        assert!(new >= moved + 4);
        assert_eq!(layout.row_count(), 3);
    }

    #[test]
    fn running_out_of_words_asks_for_a_fresh_layout() {
        let lists = vec![vec![1]; 4];
        let (mut layout, words) = SlottedRows::build(4, 0, 0, rows_of(&lists));
        assert_eq!(words.len() as u32, layout.capacity());
        let mut r = 0;
        let outcome = loop {
            match layout.place(r % 4, 1000 + r) {
                Some(_) => r += 1,
                None => break r,
            }
        };
        assert!(
            outcome < 4,
            "the capacity holds a handful of rows that size, not more"
        );
    }
}
