//! Mirror of `wgsl/proximity.wgsl`: one Jacobi pass of `collide::pull_back` over the
//! moving list, with the shader's invocations (entry, cell of the box around its tentative
//! position), loops (bucket entries, each entry's faces) and the same
//! `closest_point_on_triangle`. Faces met twice are harmless: each entry keeps the largest
//! pull-back amount, the smallest safe fraction.

use glam::{UVec3, Vec3};

use super::shared::{invocations, packed_position};
use crate::abi::{CLAMP_SLACK, MovingVertex, PULL_SCALE, ProximityParams};
use crate::geom::closest_point_on_triangle;
use crate::grid::{cell_coordinates, hash_cell};
use crate::mesh::INVALID;

const CLAMP_ROUNDS: u32 = 16;
/// What the kernel binds besides its parameters and output.
pub struct ProximityInputs<'a> {
    /// Current packed x, y, z triples.
    pub positions: &'a [f32],
    /// The hash table (`CsrTable::offsets` and `entries`).
    pub offsets: &'a [u32],
    pub entries: &'a [u32],
    /// `PackedTopology::words`.
    pub topology: &'a [u32],
    pub moving: &'a [MovingVertex],
    pub rings: &'a [u32],
    /// Per vertex; unread when `params.all_faces` is 1.
    pub marks: &'a [u32],
    /// The overlay table: per vertex nonzero when filed there, and its `offsets` and
    /// `entries`; unread unless `params.overlay`.
    pub overlay_marks: &'a [u32],
    pub overlay_offsets: &'a [u32],
    pub overlay_entries: &'a [u32],
}

/// The smallest safe fraction against the faces of vertex `u`, if `u` is within reach of `x`.
fn faces_fraction(
    params: &ProximityParams,
    inputs: &ProximityInputs<'_>,
    entry: &MovingVertex,
    u: u32,
    x: Vec3,
) -> f32 {
    let mut t = 1.0f32;
    let offset = (packed_position(inputs.positions, u) - x).abs();
    if offset.cmple(Vec3::splat(params.vertex_reach)).all() {
        let row = (params.vertex_rows_base + 2 * u) as usize;
        let first = inputs.topology[row];
        for k in first..first + inputs.topology[row + 1] {
            let f = inputs.topology[k as usize];
            t = t.min(safe_fraction(params, inputs, entry, f, x));
        }
    }
    t
}

fn distance_to_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    closest_point_on_triangle(p, a, b, c).distance(p)
}

fn touches_ring(
    inputs: &ProximityInputs<'_>,
    entry: &MovingVertex,
    a: u32,
    b: u32,
    c: u32,
) -> bool {
    let mut touches = false;
    for r in entry.ring_start..entry.ring_end {
        let w = inputs.rings[r as usize];
        touches = touches || w == a || w == b || w == c;
    }
    touches
}

fn safe_fraction(
    params: &ProximityParams,
    inputs: &ProximityInputs<'_>,
    entry: &MovingVertex,
    f: u32,
    x: Vec3,
) -> f32 {
    let words = &inputs.topology[4 * f as usize..4 * f as usize + 4];
    let (a, b, c, layer) = (words[0], words[1], words[2], words[3]);
    let (pa, pb, pc) = (
        packed_position(inputs.positions, a),
        packed_position(inputs.positions, b),
        packed_position(inputs.positions, c),
    );
    let d = params.distance;
    let near = pa.max(pb).max(pc).cmpge(x - d).all() && pa.min(pb).min(pc).cmple(x + d).all();
    if !near {
        return 1.0;
    }
    let v = entry.vertex;
    // A face the last pass left alone, unless it pulled this vertex back (short of its target
    // it can be nearer a face its move passed by).
    let marks = |u: u32| inputs.marks[u as usize];
    if params.all_faces == 0 && (marks(a) | marks(b) | marks(c) | marks(v)) == 0 {
        return 1.0;
    }
    if a == v || b == v || c == v {
        return 1.0;
    }
    if layer == entry.layer && touches_ring(inputs, entry, a, b, c) {
        return 1.0;
    }
    let here = distance_to_triangle(x, pa, pb, pc);
    if here >= d {
        return 1.0;
    }
    let start = Vec3::from_array(entry.start);
    let threshold = d.min(distance_to_triangle(start, pa, pb, pc));
    if here >= threshold - CLAMP_SLACK * d {
        return 1.0;
    }
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    for _ in 0..CLAMP_ROUNDS {
        let mid = 0.5 * (lo + hi);
        if distance_to_triangle(start + (x - start) * mid, pa, pb, pc) >= threshold {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Folds into `pulls[e]` the largest pull-back amount (65536 − 65536·t) every invocation
/// (entry, cell of its box) finds, as the kernel's atomics do; zero where nothing pulls.
pub fn proximity(params: &ProximityParams, inputs: &ProximityInputs<'_>, pulls: &mut [u32]) {
    let table_size = params.table_mask.wrapping_add(1);
    let span = UVec3::from_array(params.span);
    for i in invocations(params.count * params.cells_per_entry) {
        let e = i / params.cells_per_entry;
        let n = i % params.cells_per_entry;
        let entry = &inputs.moving[e as usize];
        let x = if entry.vertex == INVALID {
            Vec3::from_array(entry.start)
        } else {
            packed_position(inputs.positions, entry.vertex)
        };
        let mut t = 1.0f32;
        if x != Vec3::from_array(entry.start) {
            let low = cell_coordinates(x - Vec3::splat(params.cell_reach), params.inv_cell_size);
            let step = UVec3::new(n % span.x, (n / span.x) % span.y, n / (span.x * span.y));
            let cell = low + step.as_ivec3();
            let bucket = hash_cell(cell, table_size) as usize;
            for j in inputs.offsets[bucket]..inputs.offsets[bucket + 1] {
                let u = inputs.entries[j as usize];
                if params.overlay == 0 || inputs.overlay_marks[u as usize] == 0 {
                    t = t.min(faces_fraction(params, inputs, entry, u, x));
                }
            }
            if params.overlay != 0 {
                let b = hash_cell(cell, params.overlay_mask.wrapping_add(1)) as usize;
                for j in inputs.overlay_offsets[b]..inputs.overlay_offsets[b + 1] {
                    let u = inputs.overlay_entries[j as usize];
                    t = t.min(faces_fraction(params, inputs, entry, u, x));
                }
            }
        }
        if t < 1.0 {
            let amount = 65536 - (t * PULL_SCALE) as u32;
            pulls[e as usize] = pulls[e as usize].max(amount);
        }
    }
}
