//! The exact backstop, the collision response's second phase: after the proximity clamp, moves
//! are undone until no moved face crosses another, turned over, or folded onto a neighbour —
//! the edge–edge cases a vertex–triangle test cannot see. The candidate pairs come from a
//! search of the step's region, or from a filter that ran on the GPU ([`Backstop`]); the exact
//! predicates (`crate::geom`) decide them.

use glam::Vec3;
use rayon::prelude::*;

use super::region::{Region, StepMoves, map_with_scratch, start_position, triangle};
use super::state::StrokeState;
use crate::geom::{Aabb, neighbours_overlap, triangles_intersect};
use crate::mesh::{INVALID, Mesh};

/// What the first phase of a step leaves the exact backstop.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Backstop {
    /// The region was gathered (around the step's starts and targets): search it.
    Search,
    /// The region was not gathered: gather it, then search.
    Gather,
    /// The face pairs of the first round were filtered already (by the GPU): the exact
    /// predicates decide these, the ones the filter could not clear; `(f, f)` asks whether
    /// face f turned over. The region is gathered only if an undo calls for another round.
    Undecided(Vec<[u32; 2]>),
}

/// The exact backstop, [`collide_with`](super::collide_with)'s phase B: undoes moves until no
/// moved face crosses any face (edge–edge crossings and a still vertex poking through a moving
/// face are invisible to phase A, the proximity clamp). `before` holds each selected vertex's
/// start, `backstop` what phase A left to do. Returns how many moves were undone.
pub(super) fn undo_crossings(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    moves: StepMoves<'_>,
    before: &[Vec3],
    backstop: Backstop,
) -> usize {
    let (selection, _, target_of) = moves;
    let mut still_moved: Vec<bool> = selection
        .iter()
        .zip(before)
        .map(|(&(v, _), p)| mesh.positions()[v as usize] != *p)
        .collect();
    let mut reverted = 0;
    let (mut gathered, mut undecided) = match backstop {
        Backstop::Search => (true, None),
        Backstop::Gather => (false, None),
        Backstop::Undecided(pairs) => (false, Some(pairs)),
    };
    // First every moved face; after an undo, only the faces around the vertices put back (the
    // others have not moved since they were found clean).
    let mut changed: Vec<u32> = selection
        .iter()
        .zip(&still_moved)
        .filter(|(_, m)| **m)
        .map(|(&(v, _), _)| v)
        .collect();
    while !changed.is_empty() {
        let mut pairs: Vec<(u32, u32)> = match undecided.take() {
            // The filter tested exactly the pairs the search below would: the same crossings.
            Some(candidates) => {
                if region
                    .faces_around_once(mesh, changed.iter().copied())
                    .is_empty()
                {
                    break;
                }
                candidates
                    .into_iter()
                    .map(|[f, g]| (f.min(g), f.max(g)))
                    .filter(|&pair| pair_crosses(mesh, pair, target_of, before))
                    .collect()
            }
            None => {
                if !gathered {
                    gather_from_start(state, region, mesh, moves, before);
                    gathered = true;
                }
                region.find_sheets(state, mesh);
                if kept_a_lone_sheet(state, region, mesh, &changed, (target_of, before)) {
                    break;
                }
                // In the order met: the pairs found are sorted.
                let moving_faces = region.faces_around_once(mesh, changed.iter().copied());
                if moving_faces.is_empty() {
                    break;
                }
                let all_local = moving_faces.iter().all(|&f| region.local(f).is_some());
                if region.worth_searching_crossings() || !all_local {
                    region.file_faces(mesh, moves, before);
                }
                let kept =
                    kept_orientation(state, region, mesh, &moving_faces, (target_of, before));
                crossings(
                    state,
                    region,
                    mesh,
                    (&moving_faces, &kept),
                    (target_of, before),
                )
            }
        };
        if pairs.is_empty() {
            break;
        }
        pairs.sort_unstable();
        let undo = undo_pairs(mesh, pairs, (target_of, before), &mut still_moved);
        region.positions_changed();
        let undone = undo.len();
        reverted += undone;
        changed = undo;
        if undone == 0 {
            // Crossings that involve no moving vertex were there before the step.
            break;
        }
    }
    reverted
}

/// Puts every vertex of the faces of `pairs` (ascending) that is still moved back where it
/// was `before` the step, through `target_of`; returns them in the order they went back.
fn undo_pairs(
    mesh: &mut Mesh,
    pairs: Vec<(u32, u32)>,
    (target_of, before): (&[u32], &[Vec3]),
    still_moved: &mut [bool],
) -> Vec<u32> {
    let mut undo: Vec<u32> = Vec::new();
    for (f, g) in pairs {
        // (f, f) marks a face that turned over.
        for face in [f, g] {
            for v in mesh.faces()[face as usize] {
                let slot = target_of[v as usize];
                if slot != INVALID && still_moved[slot as usize] {
                    still_moved[slot as usize] = false;
                    undo.push(v);
                }
            }
        }
    }
    let positions = mesh.positions_mut();
    for &v in &undo {
        positions[v as usize] = before[target_of[v as usize] as usize];
    }
    undo
}

/// Gathers the region of a step whose selection has moved already: with the selection put back at
/// `before` meanwhile, so that it is the region [`clamp_in_region`](super::clamp_in_region)
/// gathers.
fn gather_from_start(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    (selection, targets, _): StepMoves<'_>,
    before: &[Vec3],
) {
    let now: Vec<Vec3> = selection
        .iter()
        .map(|&(v, _)| mesh.positions()[v as usize])
        .collect();
    let positions = mesh.positions_mut();
    for (&(v, _), &p) in selection.iter().zip(before) {
        positions[v as usize] = p;
    }
    region.gather_unfiled(state, mesh, selection, targets);
    let positions = mesh.positions_mut();
    for (&(v, _), p) in selection.iter().zip(now) {
        positions[v as usize] = p;
    }
}

/// Whether the region is one layer, a sheet, that holds every face around the `changed`
/// vertices, and none of those turned over in the step: then [`crossings`] skips every one of
/// them, and this finds it so without listing them. Each face is tested from the first of its
/// vertices that changed (the listing, on one thread, cost as much as the tests).
fn kept_a_lone_sheet(
    state: &StrokeState<'_>,
    region: &Region,
    mesh: &Mesh,
    changed: &[u32],
    (target_of, before): (&[u32], &[Vec3]),
) -> bool {
    if region.worth_searching_crossings() {
        return false;
    }
    // The changed vertices are selected ones: flagged by their slot in the selection.
    let mut flagged = vec![false; before.len()];
    for &v in changed {
        flagged[target_of[v as usize] as usize] = true;
    }
    let is_changed =
        |w: u32| target_of[w as usize] != INVALID && flagged[target_of[w as usize] as usize];
    let kept_around = |&v: &u32| {
        mesh.faces_around(v).all(|f| {
            let ids = mesh.faces()[f as usize];
            let first = ids.iter().position(|&w| w == v).unwrap_or(0);
            let tested_before = ids[..first].iter().any(|&w| is_changed(w));
            tested_before || (region.local(f).is_some() && !turned_over(mesh, f, target_of, before))
        })
    };
    if state.parallel {
        changed.par_iter().all(kept_around)
    } else {
        changed.iter().all(kept_around)
    }
}

/// Per layer id: whether the layer is a sheet in the region none of whose `moving_faces`
/// turned over in the step. Only those faces are searched, and only their turning over can
/// make a pair within a sheet (two faces of a sheet never meet beyond what they share,
/// `super::sheet`): where this holds, a search of them finds nothing, so it is skipped.
fn kept_orientation(
    state: &StrokeState<'_>,
    region: &Region,
    mesh: &Mesh,
    moving_faces: &[u32],
    (target_of, before): (&[u32], &[Vec3]),
) -> Vec<bool> {
    let layers = mesh.face_layers();
    let mut kept = vec![false; mesh.layer_count()];
    for (layer, kept) in kept.iter_mut().enumerate() {
        if !region.is_sheet(layer as u32) {
            continue;
        }
        let turned = |&f: &u32| {
            layers[f as usize] == layer as u32
                && region.local(f).is_some()
                && turned_over(mesh, f, target_of, before)
        };
        *kept = !if state.parallel {
            moving_faces.par_iter().any(turned)
        } else {
            moving_faces.iter().any(turned)
        };
    }
    kept
}

/// Whether face `f` turned over in the step: its normal before (vertices of the selection at
/// `before`, through `target_of`) and now point apart. A face turned over onto its neighbours
/// (a fold within a fan, which twist and pinch can make) shares vertices with everything it
/// overlaps, so no pair test sees it; its normal reversing does.
fn turned_over(mesh: &Mesh, f: u32, target_of: &[u32], before: &[Vec3]) -> bool {
    let old = mesh.faces()[f as usize].map(|w| start_position(mesh, w, target_of, before));
    let (n_old, n_new) = (face_normal(old), face_normal(triangle(mesh, f)));
    n_old.dot(n_new) <= 0.0 && n_old != Vec3::ZERO
}

/// The exact verdict on a candidate pair of the backstop: `(f, f)` whether f turned over; faces
/// sharing a vertex whether they overlap beyond it; others whether they cross.
fn pair_crosses(mesh: &Mesh, (f, g): (u32, u32), target_of: &[u32], before: &[Vec3]) -> bool {
    if f == g {
        return turned_over(mesh, f, target_of, before);
    }
    let faces = mesh.faces();
    let (tri_f, tri_g) = (triangle(mesh, f), triangle(mesh, g));
    if share_a_vertex(mesh, f, g) {
        return neighbours_overlap(tri_f, faces[f as usize], tri_g, faces[g as usize]);
    }
    apart_faces_cross(tri_f, &Aabb::of_points(&tri_f), tri_g)
}

fn share_a_vertex(mesh: &Mesh, f: u32, g: u32) -> bool {
    let faces = mesh.faces();
    faces[g as usize]
        .iter()
        .any(|v| faces[f as usize].contains(v))
}

/// Whether two faces sharing no vertex cross (`box_f` the box of `tri_f`): boxes first.
fn apart_faces_cross(tri_f: [Vec3; 3], box_f: &Aabb, tri_g: [Vec3; 3]) -> bool {
    box_f.overlaps(&Aabb::of_points(&tri_g)) && triangles_intersect(tri_f, tri_g)
}

fn face_normal(t: [Vec3; 3]) -> Vec3 {
    (t[1] - t[0]).cross(t[2] - t[0])
}

/// The crossing pairs of `moving_faces` (the region's last listed faces), searched in the gathered region: each
/// moving face against itself (turned over), the faces around its vertices (overlap beyond
/// a shared vertex) and the region's faces whose boxes meet its box. A pair of two moving
/// faces is tested from the lower one.
fn crossings(
    state: &StrokeState<'_>,
    region: &Region,
    mesh: &Mesh,
    (moving_faces, kept_orientation): (&[u32], &[bool]),
    (target_of, before): (&[u32], &[Vec3]),
) -> Vec<(u32, u32)> {
    let is_moving = |f: u32| region.is_listed(f);
    let layers = mesh.face_layers();
    // Two faces of a sheet never meet beyond what they share (`super::sheet`).
    let in_sheet = |f: u32, g: u32| {
        let layer = layers[f as usize];
        region.is_sheet(layer)
            && layers[g as usize] == layer
            && region.local(f).is_some()
            && region.local(g).is_some()
    };
    // A face of a sheet alone in the region that kept its orientation has nothing to find.
    let searched: Vec<u32> = moving_faces
        .iter()
        .copied()
        .filter(|&f| {
            !(region.single_layer()
                && in_sheet(f, f)
                && kept_orientation[layers[f as usize] as usize])
        })
        .collect();
    let found: Vec<Vec<(u32, u32)>> = map_with_scratch(state.parallel, &searched, |scratch, &f| {
        let tri_f = triangle(mesh, f);
        let box_f = Aabb::of_points(&tri_f);
        let faces = mesh.faces();
        let mut found = Vec::new();
        let layer = layers[f as usize];
        let in_sheet = |g: u32| in_sheet(f, g);
        if !(in_sheet(f) && kept_orientation[layer as usize])
            && turned_over(mesh, f, target_of, before)
        {
            found.push((f, f));
        }
        // Nor may the step fold two faces around a shared vertex onto each other: they
        // overlap while sharing a vertex, which the pair test skips.
        let ids_f = faces[f as usize];
        for w in ids_f {
            for g in mesh.faces_around(w) {
                if g == f || (g < f && is_moving(g)) || in_sheet(g) {
                    continue;
                }
                let tri_g = triangle(mesh, g);
                if neighbours_overlap(tri_f, ids_f, tri_g, faces[g as usize]) {
                    found.push((f.min(g), f.max(g)));
                }
            }
        }
        if in_sheet(f) && region.single_layer() {
            return found;
        }
        // Faces of `f`'s own sheet are skipped below: they are not even listed.
        let skip = in_sheet(f).then_some(layer);
        region.candidates_along((tri_f, skip), scratch, |local| {
            let g = region.faces[local];
            if g == f || (g < f && is_moving(g)) || in_sheet(g) || share_a_vertex(mesh, f, g) {
                return;
            }
            if apart_faces_cross(tri_f, &box_f, triangle(mesh, g)) {
                found.push((f.min(g), f.max(g)));
            }
        });
        found
    });
    found.into_iter().flatten().collect()
}
