//! Repair of a triangle soup into a mesh [`Mesh::new`](super::Mesh::new) accepts: what other
//! tools write is messier than our generators, and refusing a whole scan for one pinched vertex
//! helps nobody. Degenerate and duplicate faces are dropped, each connected part is oriented
//! one way, and vertices are split wherever the faces around them do not form one fan (two
//! fans touching at a point, an edge shared by three faces, a vertex shared by two layers).
//! Every repair is counted ([`Repairs`]), and nothing is moved: positions are copied, never
//! changed, so a repaired mesh renders exactly as the file did.

use std::fmt;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashSet;
use serde::Serialize;

use super::components::DisjointSets;
use super::{INVALID, LayerId, MeshError, face_of, next};

/// Faces and the positions they index, before any check: what a file reader builds.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Soup {
    pub positions: Vec<Vec3>,
    pub faces: Vec<[u32; 3]>,
    pub face_layers: Vec<LayerId>,
}

/// How many of each repair a soup needed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Repairs {
    /// Faces with a repeated corner or no area, dropped.
    pub degenerate_faces: usize,
    /// Faces with the same corners (in any order) as an earlier face of their layer, dropped.
    pub duplicate_faces: usize,
    /// Edges shared by more than two faces, split apart.
    pub non_manifold_edges: usize,
    /// Vertices where two or more fans of faces touched, split into one vertex per fan.
    pub non_manifold_vertices: usize,
    /// Vertices used by faces of different layers, split into one per layer.
    pub layer_shared_vertices: usize,
    /// Faces turned over so each connected part is oriented one way (the majority's).
    pub flipped_faces: usize,
    /// Edges where a part cannot be oriented (a Möbius band), cut open.
    pub non_orientable_edges: usize,
    /// Vertices no face used, dropped.
    pub unreferenced_vertices: usize,
}

impl Repairs {
    /// Whether anything was repaired.
    pub fn any(&self) -> bool {
        *self != Repairs::default()
    }
}

impl fmt::Display for Repairs {
    /// `1 non-manifold vertex split, 3 degenerate faces dropped`, or `nothing`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let items = [
            (
                self.non_manifold_vertices,
                "non-manifold vertex split",
                "non-manifold vertices split",
            ),
            (
                self.non_manifold_edges,
                "non-manifold edge split",
                "non-manifold edges split",
            ),
            (
                self.layer_shared_vertices,
                "vertex shared by layers split",
                "vertices shared by layers split",
            ),
            (
                self.degenerate_faces,
                "degenerate face dropped",
                "degenerate faces dropped",
            ),
            (
                self.duplicate_faces,
                "duplicate face dropped",
                "duplicate faces dropped",
            ),
            (
                self.flipped_faces,
                "face flipped to match its neighbours",
                "faces flipped to match their neighbours",
            ),
            (
                self.non_orientable_edges,
                "non-orientable edge cut",
                "non-orientable edges cut",
            ),
            (
                self.unreferenced_vertices,
                "unreferenced vertex dropped",
                "unreferenced vertices dropped",
            ),
        ];
        let parts: Vec<String> = items
            .iter()
            .filter(|(count, ..)| *count > 0)
            .map(|&(count, one, many)| format!("{count} {}", if count == 1 { one } else { many }))
            .collect();
        if parts.is_empty() {
            write!(f, "nothing")
        } else {
            write!(f, "{}", parts.join(", "))
        }
    }
}

/// A repaired soup, with each vertex's number in the soup it came from (`source`), so that
/// per-vertex attributes can follow.
#[derive(Debug, Clone)]
pub struct Repaired {
    pub soup: Soup,
    pub source: Vec<u32>,
    pub repairs: Repairs,
}

/// A part that still has a bad edge after this many rounds of splitting is left for
/// [`Mesh::new`](super::Mesh::new) to name; each round only separates, so two suffice in practice.
const MAX_ROUNDS: usize = 8;

/// Repairs `soup`. Only what no repair can mean is an error: an index out of range.
pub fn repair(soup: Soup) -> Result<Repaired, MeshError> {
    let Soup {
        positions,
        faces,
        face_layers,
    } = soup;
    check_indices(&faces, positions.len())?;
    let mut repairs = Repairs::default();
    let (mut faces, face_layers) = drop_bad_faces(&positions, faces, face_layers, &mut repairs);
    // Sorting the sides is most of the work on a clean mesh: done again only when the faces
    // changed.
    let mut sorted = sides(&faces);
    let cut = orient(&mut faces, &sorted, &mut repairs);
    if repairs.flipped_faces > 0 {
        sorted = sides(&faces);
    }
    let crowded = crowded_edges(&sorted);
    let mut source: Vec<u32> = (0..positions.len() as u32).collect();
    let mut split = SplitMarks::new(positions.len());
    repairs.non_manifold_edges = crowded.len();
    let clean_edges = crowded.is_empty() && cut.is_empty();
    // The ends of an edge split apart are split with it: counted as the edge's repair only.
    for &(a, b) in cut.iter().chain(&crowded) {
        split.edge_ends[a as usize] = true;
        split.edge_ends[b as usize] = true;
    }
    for round in 0..MAX_ROUNDS {
        if round > 0 {
            sorted = sides(&faces);
        }
        let marks = (&mut source, &mut split);
        let changed = split_fans(&mut faces, &sorted, &face_layers, marks, round);
        if round == 0 && !changed && clean_edges {
            break;
        }
        if changed {
            sorted = sides(&faces);
        }
        let loose = unpaired_sides_of_bad_edges(&faces, &sorted, &face_layers);
        if loose.is_empty() {
            break;
        }
        for corner in loose {
            detach_side(&mut faces, &mut source, corner);
        }
    }
    repairs.non_manifold_vertices = (0..positions.len())
        .filter(|&v| split.non_manifold[v] && !split.edge_ends[v])
        .count();
    repairs.layer_shared_vertices = split.layer_shared.iter().filter(|&&s| s).count();
    let (soup, source) = drop_unreferenced(&positions, faces, face_layers, source, &mut repairs);
    Ok(Repaired {
        soup,
        source,
        repairs,
    })
}

fn check_indices(faces: &[[u32; 3]], vertex_count: usize) -> Result<(), MeshError> {
    for (face, tri) in faces.iter().enumerate() {
        if let Some(corner) = tri.iter().position(|&v| v as usize >= vertex_count) {
            return Err(MeshError::IndexOutOfRange {
                face,
                corner: face * 3 + corner,
                vertex: tri[corner],
                vertex_count,
            });
        }
    }
    Ok(())
}

/// Drops faces with a repeated corner or exactly no area (collinear corners, in f64 where the
/// cross product of f32 differences is exact but for its last sum), and faces repeating an
/// earlier face of their layer.
fn drop_bad_faces(
    positions: &[Vec3],
    faces: Vec<[u32; 3]>,
    face_layers: Vec<LayerId>,
    repairs: &mut Repairs,
) -> (Vec<[u32; 3]>, Vec<LayerId>) {
    let mut seen: FxHashSet<(LayerId, [u32; 3])> = FxHashSet::default();
    let mut kept = (
        Vec::with_capacity(faces.len()),
        Vec::with_capacity(faces.len()),
    );
    for (tri, layer) in faces.into_iter().zip(face_layers) {
        let [a, b, c] = tri.map(|v| positions[v as usize].as_dvec3());
        let repeated = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2];
        if repeated || (b - a).cross(c - a) == DVec3::ZERO {
            repairs.degenerate_faces += 1;
            continue;
        }
        let mut sorted = tri;
        sorted.sort_unstable();
        if !seen.insert((layer, sorted)) {
            repairs.duplicate_faces += 1;
            continue;
        }
        kept.0.push(tri);
        kept.1.push(layer);
    }
    kept
}

/// Every face side (corner `c` to `next(c)`) keyed by its undirected edge, sorted: the sides
/// of one edge lie together, in corner order.
fn sides(faces: &[[u32; 3]]) -> Vec<(u64, u32)> {
    let vertex = |c: u32| faces[c as usize / 3][c as usize % 3];
    let mut keyed: Vec<(u64, u32)> = (0..faces.len() as u32 * 3)
        .into_par_iter()
        .map(|c| {
            let (a, b) = (vertex(c), vertex(next(c)));
            (((a.min(b) as u64) << 32) | a.max(b) as u64, c)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed
}

/// The runs of `sides` that share an edge.
fn edge_groups(sides: &[(u64, u32)]) -> impl Iterator<Item = &[(u64, u32)]> {
    sides.chunk_by(|x, y| x.0 == y.0)
}

/// The edges (their two vertices) shared by more than two faces.
fn crowded_edges(sides: &[(u64, u32)]) -> Vec<(u32, u32)> {
    edge_groups(sides)
        .filter(|group| group.len() > 2)
        .map(|group| ((group[0].0 >> 32) as u32, group[0].0 as u32))
        .collect()
}

/// Turns faces over so that each part joined by two-face edges is oriented one way, the way
/// most of its faces already were; returns the edges no orientation can satisfy (the fan
/// splitting then cuts them open).
fn orient(faces: &mut [[u32; 3]], sides: &[(u64, u32)], repairs: &mut Repairs) -> Vec<(u32, u32)> {
    let vertex = |c: u32| faces[c as usize / 3][c as usize % 3];
    let mut link = vec![INVALID; faces.len() * 3];
    for group in edge_groups(sides) {
        if let [(_, c), (_, d)] = *group {
            link[c as usize] = d;
            link[d as usize] = c;
        }
    }
    let mut flip: Vec<Option<bool>> = vec![None; faces.len()];
    let mut conflicts: FxHashSet<(u32, u32)> = FxHashSet::default();
    let mut part = Vec::new();
    for start in 0..faces.len() {
        if flip[start].is_some() {
            continue;
        }
        flip[start] = Some(false);
        part.clear();
        part.push(start as u32);
        let mut at = 0;
        while at < part.len() {
            let f = part[at];
            at += 1;
            let flipped = flip[f as usize] == Some(true);
            for c in f * 3..f * 3 + 3 {
                let d = link[c as usize];
                if d == INVALID {
                    continue;
                }
                let g = face_of(d);
                // Two sides starting at the same vertex run the same way: one face must turn.
                let wanted = flipped ^ (vertex(c) == vertex(d));
                match flip[g as usize] {
                    None => {
                        flip[g as usize] = Some(wanted);
                        part.push(g);
                    }
                    Some(has) if has != wanted => {
                        conflicts.insert((c.min(d), c.max(d)));
                    }
                    Some(_) => {}
                }
            }
        }
        let turned = part
            .iter()
            .filter(|&&f| flip[f as usize] == Some(true))
            .count();
        if turned * 2 > part.len() {
            for &f in &part {
                flip[f as usize] = flip[f as usize].map(|t| !t);
            }
        }
    }
    repairs.non_orientable_edges = conflicts.len();
    let cut = conflicts
        .into_iter()
        .map(|(c, _)| (vertex(c), vertex(next(c))))
        .collect();
    for (tri, flip) in faces.iter_mut().zip(flip) {
        if flip == Some(true) {
            tri.swap(1, 2);
            repairs.flipped_faces += 1;
        }
    }
    cut
}

/// Which soup vertices were split, and why.
struct SplitMarks {
    non_manifold: Vec<bool>,
    layer_shared: Vec<bool>,
    /// Ends of edges split apart, whose splits are the edge's repair.
    edge_ends: Vec<bool>,
}

impl SplitMarks {
    fn new(vertex_count: usize) -> SplitMarks {
        SplitMarks {
            non_manifold: vec![false; vertex_count],
            layer_shared: vec![false; vertex_count],
            edge_ends: vec![false; vertex_count],
        }
    }
}

/// The sides of one edge that may be glued: pairs running opposite ways on the same layer,
/// taken greedily in corner order.
fn pairs(group: &[(u64, u32)], faces: &[[u32; 3]], layers: &[LayerId]) -> Vec<(u32, u32)> {
    let vertex = |c: u32| faces[c as usize / 3][c as usize % 3];
    let mut taken = vec![false; group.len()];
    let mut found = Vec::new();
    for i in 0..group.len() {
        if taken[i] {
            continue;
        }
        let c = group[i].1;
        let partner = (i + 1..group.len()).find(|&j| {
            let d = group[j].1;
            !taken[j]
                && layers[face_of(c) as usize] == layers[face_of(d) as usize]
                && vertex(c) == vertex(next(d))
        });
        if let Some(j) = partner {
            taken[i] = true;
            taken[j] = true;
            found.push((c, group[j].1));
        }
    }
    found
}

/// Gives each fan of faces around a vertex its own vertex: corners are joined across glued
/// sides ([`pairs`]; `sides` sorted from `faces`), and every class of corners at a vertex but
/// its first gets a copy. Returns whether any vertex was split.
fn split_fans(
    faces: &mut [[u32; 3]],
    sides: &[(u64, u32)],
    layers: &[LayerId],
    (source, marks): (&mut Vec<u32>, &mut SplitMarks),
    round: usize,
) -> bool {
    let mut classes = DisjointSets::new(faces.len() * 3);
    for group in edge_groups(sides) {
        for (c, d) in pairs(group, faces, layers) {
            // Side c runs a→b and side d b→a: c's corner at a meets d's next, and the other way.
            classes.union(c, next(d));
            classes.union(next(c), d);
        }
    }
    let vertex_count = source.len();
    let mut first: Vec<(u32, LayerId)> = vec![(INVALID, 0); vertex_count];
    let mut copies = rustc_hash::FxHashMap::<u32, u32>::default();
    for c in 0..faces.len() as u32 * 3 {
        let (f, i) = (c as usize / 3, c as usize % 3);
        let v = faces[f][i];
        let class = classes.find(c);
        let layer = layers[f];
        match first[v as usize] {
            (INVALID, _) => first[v as usize] = (class, layer),
            (kept, _) if kept == class => {}
            (_, kept_layer) => {
                let original = source[v as usize] as usize;
                if kept_layer == layer || round > 0 {
                    marks.non_manifold[original] = true;
                } else {
                    marks.layer_shared[original] = true;
                }
                let copy = *copies.entry(class).or_insert_with(|| {
                    source.push(original as u32);
                    source.len() as u32 - 1
                });
                faces[f][i] = copy;
            }
        }
    }
    !copies.is_empty()
}

/// Sides of edges that are still not manifold after the fans were split (more than two faces,
/// or two running the same way): all but the glued pair, or all but the first where none is.
fn unpaired_sides_of_bad_edges(
    faces: &[[u32; 3]],
    sides: &[(u64, u32)],
    layers: &[LayerId],
) -> Vec<u32> {
    let vertex = |c: u32| faces[c as usize / 3][c as usize % 3];
    let mut loose = Vec::new();
    for group in edge_groups(sides) {
        let bad = match *group {
            [_] => false,
            [(_, c), (_, d)] => vertex(c) == vertex(d),
            _ => true,
        };
        if !bad {
            continue;
        }
        let glued = pairs(group, faces, layers);
        let keep: Vec<u32> = match glued.first() {
            Some(&(c, d)) => vec![c, d],
            None => vec![group[0].1],
        };
        loose.extend(group.iter().map(|&(_, c)| c).filter(|c| !keep.contains(c)));
    }
    loose
}

/// Gives the two ends of side `corner` vertices of their own.
fn detach_side(faces: &mut [[u32; 3]], source: &mut Vec<u32>, corner: u32) {
    for c in [corner, next(corner)] {
        let slot = &mut faces[c as usize / 3][c as usize % 3];
        source.push(source[*slot as usize]);
        *slot = source.len() as u32 - 1;
    }
}

/// Keeps the vertices faces use, in order, and counts the soup's vertices no face kept.
fn drop_unreferenced(
    positions: &[Vec3],
    mut faces: Vec<[u32; 3]>,
    face_layers: Vec<LayerId>,
    source: Vec<u32>,
    repairs: &mut Repairs,
) -> (Soup, Vec<u32>) {
    let mut used = vec![false; source.len()];
    for tri in &faces {
        for &v in tri {
            used[v as usize] = true;
        }
    }
    let mut original_used = vec![false; positions.len()];
    let mut renumber = vec![INVALID; source.len()];
    let mut kept_source = Vec::with_capacity(source.len());
    for (v, &from) in source.iter().enumerate() {
        if used[v] {
            renumber[v] = kept_source.len() as u32;
            kept_source.push(from);
            original_used[from as usize] = true;
        }
    }
    repairs.unreferenced_vertices = original_used.iter().filter(|&&u| !u).count();
    for tri in &mut faces {
        *tri = tri.map(|v| renumber[v as usize]);
    }
    let soup = Soup {
        positions: kept_source.iter().map(|&s| positions[s as usize]).collect(),
        faces,
        face_layers,
    };
    (soup, kept_source)
}

/// Only drops the vertices no face uses: what a strict import does, which refuses anything
/// else [`repair`] would change.
pub fn without_unreferenced(soup: Soup) -> Result<Repaired, MeshError> {
    check_indices(&soup.faces, soup.positions.len())?;
    let mut repairs = Repairs::default();
    let source = (0..soup.positions.len() as u32).collect();
    let (soup, source) = drop_unreferenced(
        &soup.positions,
        soup.faces,
        soup.face_layers,
        source,
        &mut repairs,
    );
    Ok(Repaired {
        soup,
        source,
        repairs,
    })
}
