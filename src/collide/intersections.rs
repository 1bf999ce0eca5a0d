//! Counting intersecting triangle pairs exactly.
//!
//! Broad phase: each face's bounding box is filed in every grid cell it overlaps (cells of about
//! two edge lengths, so a face touches a handful); faces sharing a cell are paired, and a pair is
//! counted only in the cell holding the lowest corner of the two boxes' overlap, so each pair is
//! tested once. Narrow phase: [`triangles_intersect`] on exact predicates. Pairs that share a
//! vertex touch there by construction: they count, apart, only where they meet beyond what they
//! share ([`neighbours_overlap`]: a face folded onto its neighbour, which twist, pinch, crease
//! and flips can make and the pair test alone cannot see). Faces of different layers that meet
//! only at vertex positions they share (a surface split into OBJ groups, welded by position
//! along the seam) are not crossing either: they count only where they meet beyond those
//! points ([`neighbours_overlap`]).

use glam::{I64Vec3, Vec3};
use rayon::prelude::*;

use crate::geom::{Aabb, neighbours_overlap, triangles_intersect};
use crate::mesh::{INVALID, Mesh};

/// A face spanning more cells than this is tested against every face instead of being filed
/// (only absurd input has such faces; it keeps the broad phase bounded).
const MAX_CELLS_PER_FACE: i64 = 512;
/// Cell coordinates are clamped to ±2^20 so that three fit in one `u64` key.
const CELL_LIMIT: i64 = 1 << 20;

/// Two faces that share a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct IntersectingPair {
    pub face_a: u32,
    pub face_b: u32,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub struct IntersectionReport {
    /// Intersecting pairs of faces on different layers.
    pub between_layers: usize,
    /// Intersecting pairs on the same layer that share no vertex (self-intersections).
    pub within_layers: usize,
    /// Pairs that share a vertex or an edge and overlap beyond it: a face folded onto its
    /// neighbour.
    pub folded_neighbours: usize,
    /// A few pairs, lowest face indices first, to point a user at the problem.
    pub examples: Vec<IntersectingPair>,
    /// Faces left out because a vertex is not finite.
    pub skipped_faces: usize,
}

impl IntersectionReport {
    pub fn total(&self) -> usize {
        self.between_layers + self.within_layers + self.folded_neighbours
    }
}

/// Finds every pair of live faces that intersect (closed triangles, so touching counts); pairs
/// that share a vertex count only where they overlap beyond it.
pub fn find_intersections(mesh: &Mesh) -> IntersectionReport {
    find_intersections_within(mesh, None)
}

/// [`find_intersections`] among the faces whose boxes meet `region`: every intersecting pair
/// with a face inside `region` (a pair's boxes overlap, so the other face meets it too). What
/// an edit checks after changing the faces in `region` only.
pub fn find_intersections_in(mesh: &Mesh, region: &Aabb) -> IntersectionReport {
    find_intersections_within(mesh, Some(region))
}

fn find_intersections_within(mesh: &Mesh, region: Option<&Aabb>) -> IntersectionReport {
    let (mut usable, boxes) = face_boxes(mesh);
    let skipped_faces = mesh
        .faces()
        .iter()
        .zip(&usable)
        .filter(|(t, ok)| t[0] != INVALID && !**ok)
        .count();
    if let Some(region) = region {
        for (ok, b) in usable.iter_mut().zip(&boxes) {
            *ok &= b.overlaps(region);
        }
    }
    let cells = Cells {
        size: broad_phase_cell_size(&boxes, &usable),
    };
    let (entries, oversized) = file_in_cells(&boxes, &usable, &cells);
    let pairs = PairTest { mesh };
    let mut found = pairs_in_cells(&entries, &boxes, &cells, &pairs);
    found.extend(pairs_with_oversized(&oversized, &boxes, &usable, &pairs));
    found.par_sort_unstable();
    let layers = mesh.face_layers();
    let (mut folded_neighbours, mut between_layers) = (0, 0);
    for p in &found {
        if pairs.shares_vertex(p.face_a, p.face_b) {
            folded_neighbours += 1;
        } else if layers[p.face_a as usize] != layers[p.face_b as usize] {
            between_layers += 1;
        }
    }
    IntersectionReport {
        between_layers,
        within_layers: found.len() - between_layers - folded_neighbours,
        folded_neighbours,
        examples: found.iter().take(8).copied().collect(),
        skipped_faces,
    }
}

/// Which faces can be tested (live, every corner finite), and their boxes (empty where not).
fn face_boxes(mesh: &Mesh) -> (Vec<bool>, Vec<Aabb>) {
    let positions = mesh.positions();
    let usable: Vec<bool> = mesh
        .faces()
        .par_iter()
        .map(|t| t[0] != INVALID && t.iter().all(|&v| positions[v as usize].is_finite()))
        .collect();
    let boxes = mesh
        .faces()
        .par_iter()
        .zip(&usable)
        .map(|(t, &ok)| {
            if ok {
                Aabb::of_points(&t.map(|v| positions[v as usize]))
            } else {
                Aabb::EMPTY
            }
        })
        .collect();
    (usable, boxes)
}

/// The broad phase's cubic cells.
struct Cells {
    size: f64,
}

impl Cells {
    /// The cell holding `p`, clamped to ±[`CELL_LIMIT`].
    fn of(&self, p: Vec3) -> I64Vec3 {
        let c = (p.as_dvec3() / self.size).floor();
        I64Vec3::new(c.x as i64, c.y as i64, c.z as i64)
            .clamp(I64Vec3::splat(-CELL_LIMIT), I64Vec3::splat(CELL_LIMIT - 1))
    }

    /// A cell's three coordinates in one key.
    fn key(c: I64Vec3) -> u64 {
        let b = (c + I64Vec3::splat(CELL_LIMIT)).as_u64vec3();
        (b.x << 42) | (b.y << 21) | b.z
    }
}

/// Every usable face filed in the cells its box overlaps, as (cell key, face) entries sorted by
/// cell; and the faces whose boxes span more than [`MAX_CELLS_PER_FACE`] cells, filed nowhere.
fn file_in_cells(boxes: &[Aabb], usable: &[bool], cells: &Cells) -> (Vec<(u64, u32)>, Vec<u32>) {
    type Filing = (Vec<(u64, u32)>, Option<u32>);
    let (filed, oversized): (Vec<_>, Vec<_>) = boxes
        .par_iter()
        .enumerate()
        .filter(|(f, _)| usable[*f])
        .map(|(f, b)| {
            let (lo, hi) = (cells.of(b.min), cells.of(b.max));
            let span = hi - lo + I64Vec3::ONE;
            if span.x * span.y * span.z > MAX_CELLS_PER_FACE {
                return (Vec::new(), Some(f as u32));
            }
            let mut entries = Vec::with_capacity((span.x * span.y * span.z) as usize);
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        entries.push((Cells::key(I64Vec3::new(x, y, z)), f as u32));
                    }
                }
            }
            (entries, None)
        })
        .collect::<Vec<Filing>>()
        .into_iter()
        .unzip();
    let mut entries: Vec<(u64, u32)> = filed.into_iter().flatten().collect();
    entries.par_sort_unstable();
    (entries, oversized.into_iter().flatten().collect())
}

/// The narrow phase of one pair of faces.
struct PairTest<'a> {
    mesh: &'a Mesh,
}

impl PairTest<'_> {
    fn shares_vertex(&self, a: u32, b: u32) -> bool {
        let faces = self.mesh.faces();
        faces[a as usize]
            .iter()
            .any(|v| faces[b as usize].contains(v))
    }

    /// Neighbours by [`neighbours_overlap`]; faces of different layers by
    /// [`seam_pair_intersects`]; the rest by [`triangles_intersect`].
    fn intersect(&self, a: u32, b: u32) -> bool {
        let (faces, layers) = (self.mesh.faces(), self.mesh.face_layers());
        let (ta, tb) = (
            self.mesh.face_positions(a as usize),
            self.mesh.face_positions(b as usize),
        );
        if self.shares_vertex(a, b) {
            return neighbours_overlap(ta, faces[a as usize], tb, faces[b as usize]);
        }
        if layers[a as usize] != layers[b as usize] {
            return seam_pair_intersects(ta, faces[a as usize], tb, faces[b as usize]);
        }
        triangles_intersect(ta, tb)
    }
}

/// The intersecting pairs among the faces filed in each cell, each pair tested only in the
/// cell of the lowest corner of its two boxes' overlap.
fn pairs_in_cells(
    entries: &[(u64, u32)],
    boxes: &[Aabb],
    cells: &Cells,
    pairs: &PairTest<'_>,
) -> Vec<IntersectingPair> {
    let mut group_starts: Vec<usize> = (0..entries.len())
        .into_par_iter()
        .filter(|&i| i == 0 || entries[i].0 != entries[i - 1].0)
        .collect();
    group_starts.push(entries.len());
    group_starts
        .par_windows(2)
        .flat_map_iter(|w| {
            let group = &entries[w[0]..w[1]];
            let cell_key = group[0].0;
            let mut found = Vec::new();
            for (i, &(_, a)) in group.iter().enumerate() {
                for &(_, b) in &group[i + 1..] {
                    let (ba, bb) = (&boxes[a as usize], &boxes[b as usize]);
                    if !ba.overlaps(bb) || Cells::key(cells.of(ba.min.max(bb.min))) != cell_key {
                        continue;
                    }
                    if pairs.intersect(a, b) {
                        found.push(IntersectingPair {
                            face_a: a.min(b),
                            face_b: a.max(b),
                        });
                    }
                }
            }
            found
        })
        .collect()
}

/// The intersecting pairs of each oversized face with every usable face (each pair once).
fn pairs_with_oversized(
    oversized: &[u32],
    boxes: &[Aabb],
    usable: &[bool],
    pairs: &PairTest<'_>,
) -> Vec<IntersectingPair> {
    let mut is_oversized = vec![false; boxes.len()];
    for &f in oversized {
        is_oversized[f as usize] = true;
    }
    let mut found = Vec::new();
    for &a in oversized {
        found.par_extend(
            (0..boxes.len() as u32)
                .into_par_iter()
                .filter(|&b| {
                    b != a
                        && usable[b as usize]
                        && !(is_oversized[b as usize] && b < a)
                        && boxes[a as usize].overlaps(&boxes[b as usize])
                        && pairs.intersect(a, b)
                })
                .map(|b| IntersectingPair {
                    face_a: a.min(b),
                    face_b: a.max(b),
                }),
        );
    }
    found
}

/// Whether two faces of different layers intersect, where vertices at the same position count
/// as shared: a pair meeting only at shared positions (a seam between OBJ groups) does not,
/// a pair crossing beyond them does, and two faces on the same three positions overlap whole.
fn seam_pair_intersects(a: [Vec3; 3], a_ids: [u32; 3], b: [Vec3; 3], b_ids: [u32; 3]) -> bool {
    // Give each of b's vertices that sits on one of a's the id of that vertex, so that the
    // neighbour test sees the shared points.
    let mut shared = 0;
    let b_as_a = std::array::from_fn(|j| match a.iter().position(|&p| p == b[j]) {
        Some(i) => {
            shared += 1;
            a_ids[i]
        }
        None => b_ids[j],
    });
    match shared {
        0 => triangles_intersect(a, b),
        3 => true,
        _ => neighbours_overlap(a, a_ids, b, b_as_a),
    }
}

/// Twice the mean largest box extent: a face then overlaps a few cells and a cell holds a few
/// dozen faces. Falls back to 1 for empty or degenerate input.
fn broad_phase_cell_size(boxes: &[Aabb], usable: &[bool]) -> f64 {
    let (sum, count) = boxes
        .par_iter()
        .zip(usable)
        .filter(|(_, ok)| **ok)
        .map(|(b, _)| ((b.max - b.min).max_element() as f64, 1usize))
        .reduce(|| (0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let size = 2.0 * sum / count.max(1) as f64;
    if size.is_finite() && size > 0.0 {
        size
    } else {
        1.0
    }
}
