//! The gap guard, the collision response's middle phase: the proximity clamp tests each moving
//! *vertex* against faces, so a moving *face* carried onto a still vertex of another layer (a
//! flake's sharp corner under a sheet being pushed down, the tip of a pinched ridge) is invisible
//! to it, and layers ended strokes far closer than the collision distance `d` (0.003·d after the
//! torture strokes). Here every moved face is tested against the vertices of the other layers
//! near it — still ones, and moving ones whose clamp against the face an undo may have voided:
//! a face that brought one closer than `d`, and closer than the two were at the step's start
//! (give or take the clamp's slack, as [`pull_back`](super::pull_back) allows), has its moves
//! undone, and the faces around what went back are tested again, until none is.
//!
//! Within a layer the clamp's exclusion ring decides what may come close; that is left to it.

use glam::Vec3;

use super::region::{StepMoves, map_with_scratch, triangle};
use super::state::StrokeState;
use crate::abi::CLAMP_SLACK;
use crate::geom::{Aabb, closest_point_on_triangle};
use crate::mesh::{INVALID, Mesh};

/// Undoes the moves of every moved face that came closer than the collision distance to a
/// vertex of another layer (`before`: each selected vertex's start). Returns how many vertex
/// moves were undone.
pub(super) fn undo_gap_violations(
    state: &StrokeState<'_>,
    mesh: &mut Mesh,
    (selection, _, target_of): StepMoves<'_>,
    before: &[Vec3],
) -> usize {
    let mut changed: Vec<u32> = selection
        .iter()
        .zip(before)
        .filter(|((v, _), p)| mesh.positions()[*v as usize] != **p)
        .map(|((v, _), _)| *v)
        .collect();
    // Vertices are filed in the grid where they were at the step's start: a query reaches
    // farther by the longest move.
    let drift = selection
        .iter()
        .zip(before)
        .map(|((v, _), p)| mesh.positions()[*v as usize].distance(*p))
        .fold(0.0f32, f32::max);
    let mut undone = 0;
    while !changed.is_empty() {
        let mut faces: Vec<u32> = changed.iter().flat_map(|&v| mesh.faces_around(v)).collect();
        faces.sort_unstable();
        faces.dedup();
        let view: &Mesh = mesh;
        let too_close: Vec<bool> = map_with_scratch(state.parallel, &faces, |_, &f| {
            brings_a_vertex_too_close(state, view, (f, drift), (target_of, before))
        });
        let mut back = Vec::new();
        for (&f, _) in faces.iter().zip(&too_close).filter(|(_, c)| **c) {
            for v in mesh.faces()[f as usize] {
                let slot = target_of[v as usize];
                if slot != INVALID && mesh.positions()[v as usize] != before[slot as usize] {
                    mesh.positions_mut()[v as usize] = before[slot as usize];
                    back.push(v);
                }
            }
        }
        undone += back.len();
        changed = back;
    }
    undone
}

/// Whether moved face `f` is now closer than the collision distance to a vertex of another
/// layer, and closer than the two were at the step's start. A still vertex is what the clamp
/// cannot see; a moving one was clamped against the face where it was heading, which an undo
/// since may have changed.
fn brings_a_vertex_too_close(
    state: &StrokeState<'_>,
    mesh: &Mesh,
    (f, drift): (u32, f32),
    (target_of, before): (&[u32], &[Vec3]),
) -> bool {
    let d = state.collision_distance;
    let ids = mesh.faces()[f as usize];
    let start_of = |v: u32| match target_of[v as usize] {
        INVALID => mesh.positions()[v as usize],
        slot => before[slot as usize],
    };
    if ids
        .iter()
        .all(|&v| mesh.positions()[v as usize] == start_of(v))
    {
        return false;
    }
    let now = triangle(mesh, f);
    let then = ids.map(start_of);
    let layer = mesh.face_layers()[f as usize];
    let near = Aabb::of_points(&now).expanded(d);
    let mut found = false;
    let mut test = |y: u32| {
        if found || mesh.vertex_layers()[y as usize] == layer {
            return;
        }
        let p = mesh.positions()[y as usize];
        if !(p.cmpge(near.min).all() && p.cmple(near.max).all()) {
            return;
        }
        let distance =
            |p: Vec3, t: [Vec3; 3]| closest_point_on_triangle(p, t[0], t[1], t[2]).distance(p);
        let here = distance(p, now);
        if here < d && here < d.min(distance(start_of(y), then)) - CLAMP_SLACK * d {
            found = true;
        }
    };
    match state.grid {
        Some(grid) => {
            let reach = near.expanded(drift);
            grid.for_each_in_box(reach.min, reach.max, &mut test)
        }
        None => (0..mesh.vertex_count() as u32)
            .filter(|&v| mesh.is_vertex_live(v))
            .for_each(&mut test),
    }
    found
}
