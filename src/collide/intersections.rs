//! Counting intersecting triangle pairs exactly.
//!
//! Broad phase: each face's bounding box is filed in every grid cell it overlaps (cells of about
//! two edge lengths, so a face touches a handful); faces sharing a cell are paired, and a pair is
//! counted only in the cell holding the lowest corner of the two boxes' overlap, so each pair is
//! tested once. Narrow phase: [`triangles_intersect`] on exact predicates. Pairs that share a
//! vertex touch there by construction: they count, apart, only where they meet beyond what they
//! share ([`neighbours_overlap`]: a face folded onto its neighbour, which twist, pinch, crease
//! and flips can make and the pair test alone cannot see). Most such pairs are settled before
//! that, a vertex at a time: where the faces around a shared vertex project one-to-one onto a
//! plane ([`fan_projects_one_to_one`]), no two of them meet beyond what they share, so the
//! pairs around it are not tested at all. Faces of different layers that meet
//! only at vertex positions they share (a surface split into OBJ groups, welded by position
//! along the seam) are not crossing either: they count only where they meet beyond those
//! points ([`neighbours_overlap`]).

use glam::{I64Vec3, Vec3};
use rayon::prelude::*;

use crate::geom::{Aabb, fan_projects_one_to_one, neighbours_overlap, triangles_intersect};
use crate::mesh::{INVALID, LayerId, Mesh};

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
    let filing = file_in_cells(&boxes, &usable, &cells);
    let pairs = PairTest {
        mesh,
        settled: settled_vertices(mesh, &usable),
    };
    let mut found = pairs_in_cells(&filing, &boxes, &pairs);
    found.extend(pairs_with_oversized(
        &filing.oversized,
        &boxes,
        &usable,
        &pairs,
    ));
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
pub(super) fn face_boxes(mesh: &Mesh) -> (Vec<bool>, Vec<Aabb>) {
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

/// The broad phase's filing: every usable face in the cells its box overlaps, and where each
/// face's box begins.
struct Filing {
    /// (cell key, face) for every cell a face's box overlaps, sorted by cell.
    entries: Vec<(u64, u32)>,
    /// The cell holding each face's box's lowest corner.
    lowest: Vec<I64Vec3>,
    /// The faces whose boxes span more than [`MAX_CELLS_PER_FACE`] cells, filed nowhere.
    oversized: Vec<u32>,
}

fn file_in_cells(boxes: &[Aabb], usable: &[bool], cells: &Cells) -> Filing {
    let spans: Vec<(I64Vec3, I64Vec3)> = boxes
        .par_iter()
        .map(|b| (cells.of(b.min), cells.of(b.max)))
        .collect();
    let filed = |f: usize| {
        let (lo, hi) = spans[f];
        let span = hi - lo + I64Vec3::ONE;
        usable[f] && span.x * span.y * span.z <= MAX_CELLS_PER_FACE
    };
    let oversized = (0..boxes.len())
        .filter(|&f| usable[f] && !filed(f))
        .map(|f| f as u32)
        .collect();
    let mut entries: Vec<(u64, u32)> = (0..boxes.len())
        .into_par_iter()
        .filter(|&f| filed(f))
        .flat_map_iter(|f| {
            let (lo, hi) = spans[f];
            (lo.z..=hi.z).flat_map(move |z| {
                (lo.y..=hi.y).flat_map(move |y| {
                    (lo.x..=hi.x).map(move |x| (Cells::key(I64Vec3::new(x, y, z)), f as u32))
                })
            })
        })
        .collect();
    entries.par_sort_unstable();
    Filing {
        entries,
        lowest: spans.into_iter().map(|(lo, _)| lo).collect(),
        oversized,
    }
}

/// Per vertex of a face to be tested: whether the faces around it meet only where they share
/// (their fan projects one-to-one onto a plane), so that no pair sharing it needs a test.
fn settled_vertices(mesh: &Mesh, usable: &[bool]) -> Vec<bool> {
    let mut needed = vec![false; mesh.vertex_count()];
    for (t, _) in mesh.faces().iter().zip(usable).filter(|(_, ok)| **ok) {
        for &v in t {
            needed[v as usize] = true;
        }
    }
    let positions = mesh.positions();
    needed
        .par_iter()
        .enumerate()
        .map(|(v, &needed)| {
            let v = v as u32;
            let ring = mesh.ring(v).map(|q| positions[q as usize]);
            let closed = !mesh.is_boundary_vertex(v);
            needed && fan_projects_one_to_one(positions[v as usize], ring, closed)
        })
        .collect()
}

/// The narrow phase of one pair of faces.
struct PairTest<'a> {
    mesh: &'a Mesh,
    /// Per vertex, from [`settled_vertices`].
    settled: Vec<bool>,
}

/// What the narrow phase reads of one face, gathered once for all its pairs in a cell.
struct Face {
    index: u32,
    ids: [u32; 3],
    corners: [Vec3; 3],
    layer: LayerId,
    /// Per corner: whether its vertex's faces meet only where they share.
    settled: [bool; 3],
}

impl Face {
    /// Whether the two faces share a settled vertex, and so meet only where they share.
    fn meet_only_where_shared(&self, other: &Face) -> bool {
        (0..3).any(|i| self.settled[i] && other.ids.contains(&self.ids[i]))
    }
}

impl PairTest<'_> {
    fn shares_vertex(&self, a: u32, b: u32) -> bool {
        let faces = self.mesh.faces();
        share_a_vertex(faces[a as usize], faces[b as usize])
    }

    fn face(&self, f: u32) -> Face {
        let ids = self.mesh.faces()[f as usize];
        Face {
            index: f,
            ids,
            corners: self.mesh.face_positions(f as usize),
            layer: self.mesh.face_layers()[f as usize],
            settled: ids.map(|v| self.settled[v as usize]),
        }
    }

    fn intersect(&self, a: u32, b: u32) -> bool {
        Self::faces_intersect(&self.face(a), &self.face(b))
    }

    /// Neighbours by [`neighbours_overlap`]; faces of different layers by
    /// [`seam_pair_intersects`]; the rest by [`triangles_intersect`].
    fn faces_intersect(a: &Face, b: &Face) -> bool {
        if share_a_vertex(a.ids, b.ids) {
            return neighbours_overlap(a.corners, a.ids, b.corners, b.ids);
        }
        if a.layer != b.layer {
            return seam_pair_intersects(a.corners, a.ids, b.corners, b.ids);
        }
        triangles_intersect(a.corners, b.corners)
    }
}

fn share_a_vertex(a: [u32; 3], b: [u32; 3]) -> bool {
    a.iter().any(|v| b.contains(v))
}

/// The intersecting pairs among the faces filed in each cell, each pair tested only in the
/// cell of the lowest corner of its two boxes' overlap: the higher, on each axis, of the cells
/// their lowest corners lie in (the cell of a point only grows with the point).
fn pairs_in_cells(filing: &Filing, boxes: &[Aabb], pairs: &PairTest<'_>) -> Vec<IntersectingPair> {
    let entries = &filing.entries;
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
            if group.len() < 2 {
                return Vec::new();
            }
            // Each face's box, first cell and corners read once here, not once a pair.
            let near: Vec<(Aabb, I64Vec3, Face)> = group
                .iter()
                .map(|&(_, f)| (boxes[f as usize], filing.lowest[f as usize], pairs.face(f)))
                .collect();
            let mut found = Vec::new();
            for (i, (box_a, lowest_a, a)) in near.iter().enumerate() {
                for (box_b, lowest_b, b) in &near[i + 1..] {
                    if !box_a.overlaps(box_b)
                        || a.meet_only_where_shared(b)
                        || Cells::key(lowest_a.max(*lowest_b)) != cell_key
                    {
                        continue;
                    }
                    if PairTest::faces_intersect(a, b) {
                        found.push(IntersectingPair {
                            face_a: a.index.min(b.index),
                            face_b: a.index.max(b.index),
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
