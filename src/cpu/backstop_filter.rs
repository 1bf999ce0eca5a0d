//! Mirror of `wgsl/backstop_filter.wgsl`: the f32 filter in front of the exact backstop, with the
//! shader's invocations (entry, row of cells of the box around its moved vertex), loops (the
//! first row's neighbour tests, the row's cells near the entry's faces, bucket entries, their
//! faces, the entry's faces) and tests. Pairs come
//! out in invocation order; the GPU's come in whatever order its threads ran, so compare them
//! sorted.

use glam::{IVec3, UVec3, Vec3};

use super::shared::{invocations, packed_position};
use crate::abi::{BACKSTOP_MARGIN, BackstopParams, MovingVertex};
use crate::grid::{cell_coordinates, hash_cell};
use crate::mesh::INVALID;

/// What the kernel binds besides its parameters and output.
pub struct BackstopInputs<'a> {
    /// Packed x, y, z triples after the proximity passes.
    pub positions: &'a [f32],
    /// The hash table (`CsrTable::offsets` and `entries`).
    pub offsets: &'a [u32],
    pub entries: &'a [u32],
    /// `PackedTopology::words`.
    pub topology: &'a [u32],
    pub moving: &'a [MovingVertex],
    /// Per vertex: the entry + 1 where the step moved it, else zero.
    pub moved: &'a [u32],
    /// The overlay table (unread unless `params.overlay`), as `ProximityInputs` has it.
    pub overlay_marks: &'a [u32],
    pub overlay_offsets: &'a [u32],
    pub overlay_entries: &'a [u32],
}

struct Filter<'a, 'b> {
    params: &'a BackstopParams,
    inputs: &'a BackstopInputs<'b>,
    pairs: &'a mut Vec<[u32; 2]>,
}

fn max_abs(p: Vec3) -> f32 {
    p.abs().max_element()
}

fn separates(axis: Vec3, a: [Vec3; 3], b: [Vec3; 3]) -> bool {
    let margin = BACKSTOP_MARGIN * axis.dot(axis).sqrt();
    let pa = a.map(|p| p.dot(axis));
    let pb = b.map(|p| p.dot(axis));
    let (a_lo, a_hi) = (pa[0].min(pa[1]).min(pa[2]), pa[0].max(pa[1]).max(pa[2]));
    let (b_lo, b_hi) = (pb[0].min(pb[1]).min(pb[2]), pb[0].max(pb[1]).max(pb[2]));
    margin > 0.0 && (a_hi + margin < b_lo || b_hi + margin < a_lo)
}

/// `surely_apart` of the shader: `geom::surely_disjoint` in f32, moved and scaled.
fn surely_apart_f32(a: [Vec3; 3], b: [Vec3; 3]) -> bool {
    let o = a[0];
    let scale = max_abs(a[1] - o).max(max_abs(a[2] - o)).max(
        max_abs(b[0] - o)
            .max(max_abs(b[1] - o))
            .max(max_abs(b[2] - o)),
    );
    let s = 1.0 / scale;
    let a = [Vec3::ZERO, (a[1] - o) * s, (a[2] - o) * s];
    let b = b.map(|p| (p - o) * s);
    let ea = [a[1] - a[0], a[2] - a[1], a[0] - a[2]];
    let eb = [b[1] - b[0], b[2] - b[1], b[0] - b[2]];
    let na = ea[0].cross(ea[1]);
    let nb = eb[0].cross(eb[1]);
    let mut apart = separates(na, a, b) || separates(nb, a, b);
    for i in 0..3 {
        for e in eb {
            apart = apart || separates(ea[i].cross(e), a, b);
        }
        apart = apart || separates(na.cross(ea[i]), a, b);
        apart = apart || separates(na.cross(eb[i]), a, b);
    }
    apart
}

/// `apart_at_shared_vertex` of the shader.
fn apart_at_shared_vertex(p: Vec3, a: [Vec3; 2], b: [Vec3; 2]) -> bool {
    let scale = max_abs(a[0] - p)
        .max(max_abs(a[1] - p))
        .max(max_abs(b[0] - p).max(max_abs(b[1] - p)));
    let s = 1.0 / scale;
    let [u1, u2] = a.map(|x| (x - p) * s);
    let [w1, w2] = b.map(|x| (x - p) * s);
    let (na, nb) = (u1.cross(u2), w1.cross(w2));
    let view = na * nb.dot(nb) + nb * na.dot(na);
    let margin = BACKSTOP_MARGIN * max_abs(view);
    let faces_view = na.dot(view) > margin && nb.dot(view) > margin;
    let side = |r: Vec3, x: Vec3| r.cross(x).dot(view);
    let (s11, s12, s21, s22) = (side(u1, w1), side(u1, w2), side(u2, w1), side(u2, w2));
    faces_view
        && ((s11 < -margin && s12 < -margin)
            || (s21 > margin && s22 > margin)
            || (s11 > margin && s21 > margin)
            || (s12 < -margin && s22 < -margin))
}

/// `apart_across_edge` of the shader.
fn apart_across_edge(p: Vec3, q: Vec3, a: Vec3, b: Vec3) -> bool {
    let scale = max_abs(q - p).max(max_abs(a - p).max(max_abs(b - p)));
    let s = 1.0 / scale;
    let e = (q - p) * s;
    e.cross((a - p) * s).dot(e.cross((b - p) * s)) < -BACKSTOP_MARGIN
}

impl Filter<'_, '_> {
    fn topology(&self, i: u32) -> u32 {
        self.inputs.topology[i as usize]
    }

    fn position(&self, v: u32) -> Vec3 {
        packed_position(self.inputs.positions, v)
    }

    fn old_position(&self, v: u32) -> Vec3 {
        match self.inputs.moved[v as usize] {
            0 => self.position(v),
            entry => Vec3::from_array(self.inputs.moving[entry as usize - 1].start),
        }
    }

    fn face(&self, f: u32) -> [u32; 3] {
        [
            self.topology(4 * f),
            self.topology(4 * f + 1),
            self.topology(4 * f + 2),
        ]
    }

    fn is_moved(&self, v: u32) -> bool {
        self.inputs.moved[v as usize] != 0
    }

    fn is_moving(&self, t: [u32; 3]) -> bool {
        t.iter().any(|&w| self.is_moved(w))
    }

    fn tests_face(&self, v: u32, t: [u32; 3]) -> bool {
        t.iter().all(|&w| w == v || !self.is_moved(w) || v < w)
    }

    /// The faces of `v`'s row: (first, last) word indices.
    fn row(&self, v: u32) -> (u32, u32) {
        let row = self.params.vertex_rows_base + 2 * v;
        let first = self.topology(row);
        (first, first + self.topology(row + 1))
    }

    fn append(&mut self, f: u32, g: u32) {
        self.pairs.push([f, g]);
    }

    fn neighbours_undecided(&self, tf: [u32; 3], tg: [u32; 3]) -> bool {
        let mut shared = None;
        let mut count = 0;
        for (i, a) in tf.iter().enumerate() {
            for (j, b) in tg.iter().enumerate() {
                if a == b {
                    shared.get_or_insert((i, j));
                    count += 1;
                }
            }
        }
        let p = |v: u32| self.position(v);
        match (count, shared) {
            (1, Some((i, j))) => !apart_at_shared_vertex(
                p(tf[i]),
                [p(tf[(i + 1) % 3]), p(tf[(i + 2) % 3])],
                [p(tg[(j + 1) % 3]), p(tg[(j + 2) % 3])],
            ),
            (2, _) => {
                let far_f = (0..3).rfind(|&k| !tg.contains(&tf[k])).unwrap_or(0);
                let far_g = (0..3).rfind(|&k| !tf.contains(&tg[k])).unwrap_or(0);
                !apart_across_edge(
                    p(tf[(far_f + 1) % 3]),
                    p(tf[(far_f + 2) % 3]),
                    p(tf[far_f]),
                    p(tg[far_g]),
                )
            }
            _ => true,
        }
    }

    fn may_turn_over(&self, t: [u32; 3]) -> bool {
        let o0 = self.old_position(t[0]);
        let (o1, o2) = (self.old_position(t[1]) - o0, self.old_position(t[2]) - o0);
        let p0 = self.position(t[0]);
        let (p1, p2) = (self.position(t[1]) - p0, self.position(t[2]) - p0);
        let so = 1.0 / max_abs(o1).max(max_abs(o2));
        let sp = 1.0 / max_abs(p1).max(max_abs(p2));
        let before = (o1 * so).cross(o2 * so);
        let after = (p1 * sp).cross(p2 * sp);
        // `!(x > MARGIN)`, as the shader spells it: NaN is undecided.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let undecided = !(before.dot(after) > BACKSTOP_MARGIN);
        undecided
    }

    fn test_neighbours(&mut self, v: u32, (first, last): (u32, u32)) {
        for k in first..last {
            let f = self.topology(k);
            let tf = self.face(f);
            if !self.tests_face(v, tf) {
                continue;
            }
            if self.may_turn_over(tf) {
                self.append(f, f);
            }
            for w in tf {
                let (start, end) = self.row(w);
                for kg in start..end {
                    let g = self.topology(kg);
                    let tg = self.face(g);
                    if g != f && !(g < f && self.is_moving(tg)) && self.neighbours_undecided(tf, tg)
                    {
                        self.append(f, g);
                    }
                }
            }
        }
    }

    fn test_vertex(&mut self, v: u32, (first, last): (u32, u32), u: u32, x: Vec3) {
        let offset = (self.position(u) - x).abs();
        if !offset.cmple(Vec3::splat(self.params.vertex_reach)).all() {
            return;
        }
        let (start, end) = self.row(u);
        for kg in start..end {
            let g = self.topology(kg);
            let tg = self.face(g);
            if u != tg[0].min(tg[1]).min(tg[2]) {
                continue;
            }
            let b = tg.map(|w| self.position(w));
            let (b_lo, b_hi) = (b[0].min(b[1]).min(b[2]), b[0].max(b[1]).max(b[2]));
            for k in first..last {
                let f = self.topology(k);
                let tf = self.face(f);
                let shares = tf.iter().any(|w| tg.contains(w));
                if !self.tests_face(v, tf) || shares || (g < f && self.is_moving(tg)) {
                    continue;
                }
                let a = tf.map(|w| self.position(w));
                let overlap = a[0].max(a[1]).max(a[2]).cmpge(b_lo).all()
                    && a[0].min(a[1]).min(a[2]).cmple(b_hi).all();
                if overlap && !surely_apart_f32(a, b) {
                    self.append(f, g);
                }
            }
        }
    }
}

/// The pairs every invocation (entry, row of cells of the box around its moved vertex) appends, in
/// invocation order; the kernel keeps the first `params.capacity` and counts them all.
pub fn backstop_filter(params: &BackstopParams, inputs: &BackstopInputs<'_>) -> Vec<[u32; 2]> {
    let mut pairs = Vec::new();
    let mut filter = Filter {
        params,
        inputs,
        pairs: &mut pairs,
    };
    let table_size = params.table_mask.wrapping_add(1);
    let span = UVec3::from_array(params.span);
    for i in invocations(params.count * params.cells_per_entry) {
        let e = i / params.cells_per_entry;
        let n = i % params.cells_per_entry;
        let v = inputs.moving[e as usize].vertex;
        if v == INVALID || !filter.is_moved(v) {
            continue;
        }
        let x = filter.position(v);
        let row = filter.row(v);
        if n == 0 {
            filter.test_neighbours(v, row);
        }
        let (mut lo, mut hi) = (x, x);
        let mut tests_any = false;
        for k in row.0..row.1 {
            let t = filter.face(filter.topology(k));
            if filter.tests_face(v, t) {
                tests_any = true;
                for w in t {
                    lo = lo.min(filter.position(w));
                    hi = hi.max(filter.position(w));
                }
            }
        }
        let reach = Vec3::splat(params.face_reach);
        let near_lo = cell_coordinates(lo - reach, params.inv_cell_size);
        let near_hi = cell_coordinates(hi + reach, params.inv_cell_size);
        let low = cell_coordinates(x - Vec3::splat(params.cell_reach), params.inv_cell_size);
        let row_cell = low + UVec3::new(0, n % span.y, n / span.y).as_ivec3();
        let near_row = row_cell.y >= near_lo.y
            && row_cell.z >= near_lo.z
            && row_cell.y <= near_hi.y
            && row_cell.z <= near_hi.z;
        if !(tests_any && near_row) {
            continue;
        }
        for step in 0..span.x {
            let cell = row_cell + IVec3::new(step as i32, 0, 0);
            if cell.x < near_lo.x || cell.x > near_hi.x {
                continue;
            }
            let bucket = hash_cell(cell, table_size) as usize;
            for j in inputs.offsets[bucket]..inputs.offsets[bucket + 1] {
                let u = inputs.entries[j as usize];
                if params.overlay == 0 || inputs.overlay_marks[u as usize] == 0 {
                    filter.test_vertex(v, row, u, x);
                }
            }
            if params.overlay != 0 {
                let b = hash_cell(cell, params.overlay_mask.wrapping_add(1)) as usize;
                for j in inputs.overlay_offsets[b]..inputs.overlay_offsets[b + 1] {
                    filter.test_vertex(v, row, inputs.overlay_entries[j as usize], x);
                }
            }
        }
    }
    pairs
}
