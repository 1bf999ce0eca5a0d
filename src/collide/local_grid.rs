//! A dense grid of face boxes over one brush step's region: the collision broad phase.
//!
//! The global spatial hash files vertices; a proximity query through it must probe every cell
//! within `d + longest edge` of the point (over a hundred hash probes). Per step we instead
//! gather the region's faces once through the hash and file their boxes in a small dense array
//! (counting sort, no hashing), so a query reads only the few cells its own box covers.

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use crate::geom::{Aabb, Polygon};

/// Cells per axis at most for a grid of few faces; larger regions get larger cells…
const MAX_CELLS_PER_AXIS: f32 = 64.0;
/// …unless the grid files many faces: then up to this many cells a face. A whole-mesh remesh
/// files every face; held to 64 cells an axis, a 1M-face torus had cells 7 edges wide and
/// every query read hundreds of faces.
const MAX_CELLS_PER_FACE: usize = 8;
/// Faces one job of a parallel filing takes at least: listing a face's cells is well under a
/// microsecond.
const FACES_PER_JOB: usize = 1024;

#[derive(Debug, Clone, Default)]
pub struct LocalFaceGrid {
    origin: Vec3,
    inv_cell: f32,
    dims: IVec3,
    /// `offsets[c]..offsets[c + 1]` indexes `entries` for cell `c`.
    offsets: Vec<u32>,
    /// Local face indices (positions in the face list the grid was built from).
    entries: Vec<u32>,
    cursor: Vec<u32>,
    /// [`LocalFaceGrid::build_swept`]'s cells of every face, face after face, and where each
    /// face's cells end.
    spill: Vec<u32>,
    spill_ends: Vec<u32>,
}

/// A face where a step starts, and the box of its corners' moves over the step (holding zero):
/// wherever its corners are along their moves, the face lies in the triangle swept by the box.
#[derive(Debug, Clone, Copy)]
pub struct SweptTriangle {
    pub corners: [Vec3; 3],
    pub moves: Aabb,
}

impl SweptTriangle {
    /// No move: a face at rest.
    pub const NO_MOVE: Aabb = Aabb {
        min: Vec3::ZERO,
        max: Vec3::ZERO,
    };

    /// A face that does not move.
    pub fn at_rest(corners: [Vec3; 3]) -> SweptTriangle {
        SweptTriangle {
            corners,
            moves: SweptTriangle::NO_MOVE,
        }
    }
}

/// A face whose box spans more cells than this is filed only in the cells it can pass
/// through: a surface stretched far past its edge length (a sweep dragging all of a sphere
/// nine of its radii) had faces up to 135 edges long whose boxes covered up to 10⁴ cells,
/// 57 times the entries of the unstretched mesh, and every query met them.
const SWEPT_ABOVE_CELLS: i32 = 8;

impl LocalFaceGrid {
    /// Files `boxes[i]` (local face `i`) in every cell it overlaps. `region` bounds all boxes;
    /// `cell` is the preferred cell side.
    pub fn build(&mut self, boxes: &[Aabb], region: Aabb, cell: f32) {
        self.size(boxes.len(), region, cell);
        for b in boxes {
            let (lo, hi) = self.cell_span(b);
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let c = self.index(IVec3::new(x, y, z));
                        self.offsets[c + 1] += 1;
                    }
                }
            }
        }
        let mut cursor = self.counted();
        for (i, b) in boxes.iter().enumerate() {
            let (lo, hi) = self.cell_span(b);
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let c = self.index(IVec3::new(x, y, z));
                        self.entries[cursor[c] as usize] = i as u32;
                        cursor[c] += 1;
                    }
                }
            }
        }
        self.cursor = cursor;
    }

    /// Files local face `i` in the cells of `boxes[i]` that `swept[i]` can pass through (all
    /// of them for a face of a few cells): a query box meets a face only where the face may
    /// be. `region` bounds all boxes; `cell` is the preferred cell side.
    pub fn build_swept(
        &mut self,
        boxes: &[Aabb],
        swept: &[SweptTriangle],
        region: Aabb,
        cell: f32,
    ) {
        debug_assert_eq!(boxes.len(), swept.len(), "one swept face per box");
        self.build_swept_of((boxes, swept, None), region, cell);
    }

    /// [`LocalFaceGrid::build_swept`] of some local faces: `boxes[i]` and `swept[i]` are
    /// local face `ids[i]`'s.
    pub fn build_some_swept(
        &mut self,
        (boxes, swept, ids): (&[Aabb], &[SweptTriangle], &[u32]),
        region: Aabb,
        cell: f32,
    ) {
        debug_assert!(boxes.len() == ids.len() && swept.len() == ids.len());
        self.build_swept_of((boxes, swept, Some(ids)), region, cell);
    }

    fn build_swept_of(
        &mut self,
        (boxes, swept, ids): (&[Aabb], &[SweptTriangle], Option<&[u32]>),
        region: Aabb,
        cell: f32,
    ) {
        self.size(boxes.len(), region, cell);
        let mut spill = std::mem::take(&mut self.spill);
        let mut ends = std::mem::take(&mut self.spill_ends);
        spill.clear();
        ends.clear();
        if boxes.len() <= FACES_PER_JOB {
            self.spill_cells((boxes, swept), &mut spill, &mut ends);
        } else {
            // Which cells a face reaches is its own: listed on every core, chunk by chunk,
            // then joined in face order.
            let chunks: Vec<(Vec<u32>, Vec<u32>)> = (boxes.par_chunks(FACES_PER_JOB))
                .zip(swept.par_chunks(FACES_PER_JOB))
                .map(|chunk| {
                    let (mut cells, mut chunk_ends) = (Vec::new(), Vec::new());
                    self.spill_cells(chunk, &mut cells, &mut chunk_ends);
                    (cells, chunk_ends)
                })
                .collect();
            for (cells, chunk_ends) in chunks {
                let base = spill.len() as u32;
                spill.extend_from_slice(&cells);
                ends.extend(chunk_ends.iter().map(|end| base + end));
            }
        }
        for &c in &spill {
            self.offsets[c as usize + 1] += 1;
        }
        let mut cursor = self.counted();
        let mut start = 0;
        for (i, &end) in ends.iter().enumerate() {
            let id = ids.map_or(i as u32, |ids| ids[i]);
            for &c in &spill[start..end as usize] {
                self.entries[cursor[c as usize] as usize] = id;
                cursor[c as usize] += 1;
            }
            start = end as usize;
        }
        self.cursor = cursor;
        self.spill = spill;
        self.spill_ends = ends;
    }

    /// The cells each face can reach ([`LocalFaceGrid::swept_cells`]), face after face into
    /// `spill`, and where each face's cells end into `ends`.
    fn spill_cells(
        &self,
        (boxes, swept): (&[Aabb], &[SweptTriangle]),
        spill: &mut Vec<u32>,
        ends: &mut Vec<u32>,
    ) {
        for (b, s) in boxes.iter().zip(swept) {
            self.swept_cells(b, s, spill);
            ends.push(spill.len() as u32);
        }
    }

    /// The cells of `b` (the box of `swept`) that the swept face can reach, into `out`. A
    /// point `p + m` of it (`p` on the triangle, `m` in the move box) lies in cell (x, y, z)
    /// only if `p` lies in that cell's z slab widened by the move box, and within it in the
    /// y row widened likewise; the x cells then follow from that part's x range. Slabs are
    /// widened by a slack above the clipping's rounding, and the border cells reach out to
    /// infinity as [`LocalFaceGrid::cell_span`] clamps.
    fn swept_cells(&self, b: &Aabb, swept: &SweptTriangle, out: &mut Vec<u32>) {
        let (lo, hi) = self.cell_span(b);
        let span = hi - lo + IVec3::ONE;
        if span.x * span.y * span.z <= SWEPT_ABOVE_CELLS {
            self.for_each_cell((lo, hi), |c, _| out.push(c as u32));
            return;
        }
        let scale = b.min.abs().max(b.max.abs()).max_element();
        let slack = 1e-3 / self.inv_cell + 8.0 * f32::EPSILON * scale;
        let moves = swept.moves;
        let triangle = Polygon::triangle(swept.corners);
        for z in lo.z..=hi.z {
            let (z0, z1) = self.slab(2, z, &moves, slack);
            let in_z = triangle.within_slab(2, z0, z1);
            let Some((y_lo, y_hi)) = in_z.range(1) else {
                continue;
            };
            let rows = (y_lo + moves.min.y - slack, y_hi + moves.max.y + slack);
            let rows = (
                self.cell_of(1, rows.0).max(lo.y),
                self.cell_of(1, rows.1).min(hi.y),
            );
            for y in rows.0..=rows.1 {
                let (y0, y1) = self.slab(1, y, &moves, slack);
                let Some((x_lo, x_hi)) = in_z.within_slab(1, y0, y1).range(0) else {
                    continue;
                };
                let first = self.cell_of(0, x_lo + moves.min.x - slack).max(lo.x);
                let last = self.cell_of(0, x_hi + moves.max.x + slack).min(hi.x);
                for x in first..=last {
                    out.push(self.index(IVec3::new(x, y, z)) as u32);
                }
            }
        }
    }

    /// Where a point of a triangle must be along `axis` for the triangle moved by some `m` in
    /// `moves` to reach cell row `k` there, give or take `slack`.
    fn slab(&self, axis: usize, k: i32, moves: &Aabb, slack: f32) -> (f32, f32) {
        let cell = 1.0 / self.inv_cell;
        let lower = match k {
            0 => f32::NEG_INFINITY,
            _ => self.origin[axis] + k as f32 * cell,
        };
        let upper = match k == self.dims[axis] - 1 {
            true => f32::INFINITY,
            false => self.origin[axis] + (k + 1) as f32 * cell,
        };
        (
            lower - moves.max[axis] - slack,
            upper - moves.min[axis] + slack,
        )
    }

    /// The cell row along `axis` holding `value`, clamped to the grid as queries are.
    fn cell_of(&self, axis: usize, value: f32) -> i32 {
        let row = ((value - self.origin[axis]) * self.inv_cell).max(0.0) as i32;
        row.min(self.dims[axis] - 1)
    }

    /// Once `offsets[c + 1]` holds how many entries cell `c` gets: turns the counts into
    /// offsets, sizes the entries, and returns where each cell's next entry goes.
    fn counted(&mut self) -> Vec<u32> {
        let cell_count = self.offsets.len() - 1;
        for c in 0..cell_count {
            self.offsets[c + 1] += self.offsets[c];
        }
        self.entries.clear();
        self.entries.resize(self.offsets[cell_count] as usize, 0);
        let mut cursor = std::mem::take(&mut self.cursor);
        cursor.clear();
        cursor.extend_from_slice(&self.offsets);
        cursor
    }

    /// Sizes the grid for `faces` boxes within `region`, all cells empty.
    fn size(&mut self, faces: usize, region: Aabb, cell: f32) {
        let extent = (region.max - region.min).max(Vec3::splat(cell));
        let axis_cap = MAX_CELLS_PER_AXIS.powi(3) as usize;
        let mut cell = cell;
        if faces * MAX_CELLS_PER_FACE <= axis_cap {
            cell = cell.max(extent.max_element() / MAX_CELLS_PER_AXIS);
        } else {
            let cells = |cell: f32| {
                let dims = (extent / cell).floor() + Vec3::ONE;
                dims.x as f64 * dims.y as f64 * dims.z as f64
            };
            while cells(cell) > (faces * MAX_CELLS_PER_FACE) as f64 {
                cell *= 1.25;
            }
        }
        self.origin = region.min;
        self.inv_cell = 1.0 / cell;
        self.dims = ((extent * self.inv_cell).floor().as_ivec3() + IVec3::ONE).max(IVec3::ONE);
        let cell_count = (self.dims.x * self.dims.y * self.dims.z) as usize;
        self.offsets.clear();
        self.offsets.resize(cell_count + 1, 0);
    }

    /// Calls `f` with every local face filed in a cell overlapping `query` (a face may come
    /// more than once; callers deduplicate).
    pub fn for_each_candidate(&self, query: &Aabb, mut f: impl FnMut(u32)) {
        if self.offsets.is_empty() {
            return;
        }
        self.for_each_cell(self.cell_span(query), |c, _| {
            for &e in &self.entries[self.offsets[c] as usize..self.offsets[c + 1] as usize] {
                f(e);
            }
        });
    }

    /// Calls `f` with every local face filed in a cell that `swept` (whose box is `query`)
    /// can pass through, as [`LocalFaceGrid::build_swept`] files faces (`cells` is scratch; a
    /// face may come more than once): what can meet a long face, without the whole of its box.
    pub fn for_each_candidate_along(
        &self,
        query: &Aabb,
        swept: &SweptTriangle,
        cells: &mut Vec<u32>,
        mut f: impl FnMut(u32),
    ) {
        if self.offsets.is_empty() {
            return;
        }
        cells.clear();
        self.swept_cells(query, swept, cells);
        for &c in cells.iter() {
            let c = c as usize;
            for &e in &self.entries[self.offsets[c] as usize..self.offsets[c + 1] as usize] {
                f(e);
            }
        }
    }

    /// Calls `f` once with every local face filed in a cell overlapping `query` (`boxes` the
    /// boxes the grid was built from): a face is taken only in the lowest cell that both its
    /// box and the query cover, with no list to sort and deduplicate.
    pub fn for_each_face_once(&self, query: &Aabb, boxes: &[Aabb], mut f: impl FnMut(u32)) {
        if self.offsets.is_empty() {
            return;
        }
        let span = self.cell_span(query);
        self.for_each_cell(span, |c, at| {
            for &e in &self.entries[self.offsets[c] as usize..self.offsets[c + 1] as usize] {
                if self.cell_span(&boxes[e as usize]).0.max(span.0) == at {
                    f(e);
                }
            }
        });
    }

    /// Calls `f` with the index and coordinates of every cell of `span`.
    pub fn for_each_cell(&self, (lo, hi): (IVec3, IVec3), mut f: impl FnMut(usize, IVec3)) {
        if self.offsets.is_empty() {
            return;
        }
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let at = IVec3::new(x, y, z);
                    f(self.index(at), at);
                }
            }
        }
    }

    /// Whether `f` holds for some local face filed in a cell overlapping `query`; stops at the
    /// first.
    pub fn any_candidate(&self, query: &Aabb, mut f: impl FnMut(u32) -> bool) -> bool {
        if self.offsets.is_empty() {
            return false;
        }
        let (lo, hi) = self.cell_span(query);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let c = self.index(IVec3::new(x, y, z));
                    let cell =
                        &self.entries[self.offsets[c] as usize..self.offsets[c + 1] as usize];
                    if cell.iter().any(|&e| f(e)) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// The cells overlapping `b`, lowest and highest (clamped to the grid, as filing and
    /// queries are): also for callers that file more faces beside the grid's own.
    pub fn cell_span(&self, b: &Aabb) -> (IVec3, IVec3) {
        // Truncation is floor here: everything below the origin clamps to cell 0 anyway.
        let clamp = |p: Vec3| {
            ((p - self.origin) * self.inv_cell)
                .max(Vec3::ZERO)
                .as_ivec3()
                .min(self.dims - IVec3::ONE)
        };
        (clamp(b.min), clamp(b.max))
    }

    #[inline]
    fn index(&self, c: IVec3) -> usize {
        ((c.z * self.dims.y + c.y) * self.dims.x + c.x) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn point(scale: f32) -> impl Strategy<Value = Vec3> {
        let axis = move || -scale..scale;
        (axis(), axis(), axis()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    /// Faces of a few cells' size and faces stretched across the grid, each moving or not.
    fn swept_face() -> impl Strategy<Value = SweptTriangle> {
        let size = prop_oneof![Just(0.05f32), Just(2.0f32)];
        (
            size,
            point(1.0),
            point(1.0),
            point(1.0),
            prop::option::of(point(0.1)),
        )
            .prop_map(|(size, at, a, b, moved)| {
                let corners = [at, at + a * size, at + b * size];
                let moves = SweptTriangle::NO_MOVE;
                let moves = moved.map_or(moves, |m| moves.including(m).including(-0.5 * m));
                SweptTriangle { corners, moves }
            })
    }

    fn swept_box(s: &SweptTriangle) -> Aabb {
        let start = Aabb::of_points(&s.corners);
        Aabb {
            min: start.min + s.moves.min,
            max: start.max + s.moves.max,
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        /// Every point a swept face can take (a point of the triangle moved by anything in its
        /// move box) is in a cell the face is filed in, so a query box around it meets the face;
        /// the faces stretched across the grid are filed in fewer cells than their boxes cover.
        #[test]
        fn a_swept_face_is_filed_wherever_it_can_be(
            faces in prop::collection::vec(swept_face(), 1..12),
            picks in prop::collection::vec((0.0f32..=1.0, 0.0f32..=1.0, point(1.0)), 32),
        ) {
            let boxes: Vec<Aabb> = faces.iter().map(swept_box).collect();
            let region = boxes.iter().fold(Aabb::EMPTY, |b, f| b.including_box(f));
            let mut grid = LocalFaceGrid::default();
            grid.build_swept(&boxes, &faces, region, 0.02);
            for (i, face) in faces.iter().enumerate() {
                let [a, b, c] = face.corners;
                for &(u, v, m) in &picks {
                    let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                    let on_triangle = a + (b - a) * u + (c - a) * v;
                    let m = (m * 0.5 + Vec3::splat(0.5)) * (face.moves.max - face.moves.min);
                    let p = on_triangle + face.moves.min + m;
                    let mut met = false;
                    grid.for_each_candidate(&Aabb { min: p, max: p }, |e| met |= e == i as u32);
                    prop_assert!(met, "face {i} not filed where it reaches {p}");
                }
            }
            let mut box_cells = 0;
            for b in &boxes {
                let (lo, hi) = grid.cell_span(b);
                let span = hi - lo + IVec3::ONE;
                box_cells += span.x * span.y * span.z;
            }
            prop_assert!(grid.entries.len() <= box_cells as usize);
        }
    }

    /// Enough faces to be listed chunk by chunk on several threads are filed as one thread
    /// files them: every cell holds, in ascending order, exactly the faces whose cells include it.
    #[test]
    fn faces_listed_in_parallel_are_filed_in_face_order() {
        use proptest::strategy::ValueTree;
        let mut runner = proptest::test_runner::TestRunner::deterministic();
        let faces: Vec<SweptTriangle> = (0..3 * FACES_PER_JOB + 17)
            .map(|_| swept_face().new_tree(&mut runner).unwrap().current())
            .collect();
        let boxes: Vec<Aabb> = faces.iter().map(swept_box).collect();
        let region = boxes.iter().fold(Aabb::EMPTY, |b, f| b.including_box(f));
        let mut grid = LocalFaceGrid::default();
        grid.build_swept(&boxes, &faces, region, 0.05);
        let mut expected = vec![Vec::new(); grid.offsets.len() - 1];
        let mut cells = Vec::new();
        for (i, (b, face)) in boxes.iter().zip(&faces).enumerate() {
            cells.clear();
            grid.swept_cells(b, face, &mut cells);
            for &c in &cells {
                expected[c as usize].push(i as u32);
            }
        }
        for (c, want) in expected.iter().enumerate() {
            let filed = &grid.entries[grid.offsets[c] as usize..grid.offsets[c + 1] as usize];
            assert_eq!(filed, &want[..], "cell {c}");
        }
    }

    /// A face sixty cells long across the grid's diagonal is filed along its length, not in
    /// every cell of its box.
    #[test]
    fn a_long_diagonal_face_is_filed_along_its_length() {
        let face = SweptTriangle::at_rest([
            Vec3::ZERO,
            Vec3::new(2.0, 2.0, 0.0),
            Vec3::new(2.01, 1.99, 0.0),
        ]);
        let boxes = [Aabb::of_points(&face.corners)];
        let mut grid = LocalFaceGrid::default();
        grid.build_swept(&boxes, &[face], boxes[0].expanded(0.1), 0.02);
        let (lo, hi) = grid.cell_span(&boxes[0]);
        let span = hi - lo + IVec3::ONE;
        let box_cells = (span.x * span.y * span.z) as usize;
        assert!(box_cells > 3_000, "{box_cells} cells in the box");
        assert!(
            grid.entries.len() < box_cells / 10,
            "{} cells filed",
            grid.entries.len()
        );
        let mut met = false;
        let far_corner = Aabb::of_points(&[Vec3::new(1.99, 0.01, 0.0)]);
        grid.for_each_candidate(&far_corner, |_| met = true);
        assert!(!met, "the empty corner of the box holds the face");
    }
}
