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

use super::LocalFaceGrid;
use super::region::{Region, StepMoves, map_with_scratch, start_position, triangle};
use super::state::StrokeState;
use crate::abi::CLAMP_SLACK;
use crate::geom::{Aabb, point_triangle_distance};
use crate::mesh::{INVALID, Mesh};

/// Undoes the moves of every face and vertex of different layers that came closer than the
/// collision distance (`before`: each selected vertex's start). Returns how many vertex moves
/// were undone.
pub(super) fn undo_gap_violations(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    (selection, _, target_of): StepMoves<'_>,
    before: &[Vec3],
) -> usize {
    // Vertices are filed in the grid where they were at the step's start: a query for moving
    // ones reaches farther by the longest move.
    let drift = selection
        .iter()
        .zip(before)
        .map(|((v, _), p)| mesh.positions()[*v as usize].distance(*p))
        .fold(0.0f32, f32::max);
    if alone_in_region(state, region, mesh, (selection, before), drift) {
        return 0;
    }
    // The first round tests the faces around the whole selection: what moved, and what the
    // clamp or the backstop stopped or put back (a face there may now be where a moving vertex
    // was not clamped against). Later rounds test around what is still moved (an undo can
    // leave a moved face nearer a vertex that went back) and what went back.
    let mut went_back: Vec<u32> = selection.iter().map(|&(v, _)| v).collect();
    let mut undone = 0;
    loop {
        let moved = selection
            .iter()
            .zip(before)
            .filter(|((v, _), p)| mesh.positions()[*v as usize] != **p)
            .map(|((v, _), _)| *v);
        let view: &Mesh = mesh;
        // In the order met: what is found does not depend on it.
        let faces = region.faces_around_once(view, moved.chain(went_back.iter().copied()));
        let region: &Region = region;
        let others = other_layers_near(state, region, view, &faces, drift);
        if others.as_ref().is_some_and(|near| near.vertices.is_empty()) {
            return undone;
        }
        let too_close: Vec<Vec<u32>> = map_with_scratch(state.parallel, &faces, |_, &f| {
            vertices_too_close(
                state,
                view,
                (f, drift),
                (target_of, before),
                others.as_ref(),
            )
        });
        // Each pair goes back to where both were at the step's start, where they were apart
        // enough: the face's moved vertices, and every vertex too close to it that moved (all
        // of them: the face is not looked at again once it is back).
        let mut back = Vec::new();
        for (&f, near) in faces.iter().zip(too_close) {
            if near.is_empty() {
                continue;
            }
            for v in mesh.faces()[f as usize].into_iter().chain(near) {
                let slot = target_of[v as usize];
                if slot != INVALID && mesh.positions()[v as usize] != before[slot as usize] {
                    mesh.positions_mut()[v as usize] = before[slot as usize];
                    back.push(v);
                }
            }
        }
        if back.is_empty() {
            return undone;
        }
        undone += back.len();
        went_back = back;
    }
}

/// Whether the first round would find no vertex of another layer to test, known without
/// listing the faces around the selection: when the region holds every vertex the round could
/// test and all of them are of one layer, that round finds nothing and there is no other.
///
/// The round's query ([`other_layers_near`]) is the box of the faces around the selection,
/// grown by `d` and the drift. Their corners are the selection, where it started or is now,
/// and still neighbours, each within an edge of a selected vertex's start: every edge was at
/// most `max_edge` long when the step began. So the box of the starts and the positions now,
/// grown by `max_edge` (and a margin for rounding), holds that box.
fn alone_in_region(
    state: &StrokeState<'_>,
    region: &Region,
    mesh: &Mesh,
    (selection, before): (&[(u32, f32)], &[Vec3]),
    drift: f32,
) -> bool {
    let Some(&(first, _)) = selection.first() else {
        return false;
    };
    let layers = mesh.vertex_layers();
    let layer = layers[first as usize];
    if !state.cull
        || region
            .vertices()
            .iter()
            .any(|&y| layers[y as usize] != layer)
    {
        return false;
    }
    let positions = mesh.positions();
    let now = selection.iter().map(|&(v, _)| positions[v as usize]);
    let corners = before
        .iter()
        .copied()
        .chain(now)
        .fold(Aabb::EMPTY, |b, p| b.including(p));
    let scale = corners.min.abs().max(corners.max.abs()).max_element();
    let edge = state.max_edge * 1.001 + 4.0 * f32::EPSILON * scale;
    let near = corners.expanded(edge).expanded(state.collision_distance);
    region.covers(&near.expanded(drift))
}

/// The vertices of other layers that face `f` (around a vertex that moved or went back) is now
/// closer to than the collision distance, and than each was at the step's start. A still
/// vertex under a moving face is what the clamp cannot see; a moving one was clamped against
/// the face where it was heading, which an undo since may have changed.
fn vertices_too_close(
    state: &StrokeState<'_>,
    mesh: &Mesh,
    (f, drift): (u32, f32),
    (target_of, before): (&[u32], &[Vec3]),
    others: Option<&OtherLayers>,
) -> Vec<u32> {
    let d = state.collision_distance;
    let ids = mesh.faces()[f as usize];
    let start_of = |v: u32| start_position(mesh, v, target_of, before);
    let face_moved = ids
        .iter()
        .any(|&v| mesh.positions()[v as usize] != start_of(v));
    let now = triangle(mesh, f);
    let then = ids.map(start_of);
    let layer = mesh.face_layers()[f as usize];
    let near = Aabb::of_points(&now).expanded(d);
    let mut found = Vec::new();
    let mut test = |y: u32| {
        if mesh.vertex_layers()[y as usize] == layer {
            return;
        }
        let p = mesh.positions()[y as usize];
        // A still face and a still vertex are as far apart as they were.
        if !face_moved && p == start_of(y) {
            return;
        }
        if !(p.cmpge(near.min).all() && p.cmple(near.max).all()) {
            return;
        }
        let here = point_triangle_distance(p, now);
        if here < d && here < d.min(point_triangle_distance(start_of(y), then)) - CLAMP_SLACK * d {
            found.push(y);
        }
    };
    match (others, state.grid) {
        (Some(others), _) => others
            .grid
            .for_each_candidate(&near, |i| test(others.vertices[i as usize])),
        (None, Some(grid)) => {
            let reach = near.expanded(drift);
            grid.for_each_in_box(reach.min, reach.max, &mut test)
        }
        (None, None) => (0..mesh.vertex_count() as u32)
            .filter(|&v| mesh.is_vertex_live(v))
            .for_each(&mut test),
    }
    found
}

/// The vertices that a round's faces could be too close to, where the step's region holds
/// them all: those of other layers than the faces', filed where they are now. None when the
/// region does not reach that far (or culling is off): search the grid face by face.
struct OtherLayers {
    vertices: Vec<u32>,
    grid: LocalFaceGrid,
}

/// Vertices per face past which the faces probe the global grid instead of filing them.
const PROBE_INSTEAD: usize = 16;

fn other_layers_near(
    state: &StrokeState<'_>,
    region: &Region,
    mesh: &Mesh,
    faces: &[u32],
    drift: f32,
) -> Option<OtherLayers> {
    let d = state.collision_distance;
    let near = faces
        .iter()
        .fold(Aabb::EMPTY, |b, &f| {
            b.including_box(&Aabb::of_points(&triangle(mesh, f)))
        })
        .expanded(d);
    if !state.cull || faces.is_empty() || !region.covers(&near.expanded(drift)) {
        return None;
    }
    let face_layers = mesh.face_layers();
    let first = face_layers[faces[0] as usize];
    let one_layer = faces.iter().all(|&f| face_layers[f as usize] == first);
    let vertex_layers = mesh.vertex_layers();
    // With faces of several layers every vertex may be of another layer than one of them.
    let vertices: Vec<u32> = region
        .vertices()
        .iter()
        .copied()
        .filter(|&y| !one_layer || vertex_layers[y as usize] != first)
        .collect();
    // Filing costs per vertex what a probe of the global grid costs per face over a few
    // dozen cells: with few faces among many vertices, probing is cheaper (and finds the
    // same).
    if vertices.len() > PROBE_INSTEAD * faces.len() {
        return None;
    }
    let mut grid = LocalFaceGrid::default();
    if !vertices.is_empty() {
        let points: Vec<Aabb> = vertices
            .iter()
            .map(|&y| Aabb::of_points(&[mesh.positions()[y as usize]]))
            .collect();
        let bounds = points.iter().fold(near, |b, p| b.including_box(p));
        grid.build(&points, bounds, d);
    }
    Some(OtherLayers { vertices, grid })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::SpatialHash;
    use crate::scene::shapes;

    /// Two sheets `gap` apart, a patch of the lower one lifted a little: whether the guard's
    /// first round is skipped, and what that round would have had to test.
    fn skip_and_round(gap: f32) -> (bool, Option<usize>) {
        let mesh = shapes::stacked_sheets(2, 16, 16, 1.0, gap);
        let grid = SpatialHash::build(&mesh, 1.0).unwrap();
        let active = vec![true; mesh.layer_count()];
        let state = StrokeState::for_tests(&grid, &active, mesh.longest_edge() * 1.1);
        let selection: Vec<(u32, f32)> = [7 * 17 + 7, 7 * 17 + 8, 8 * 17 + 7, 8 * 17 + 8]
            .iter()
            .map(|&v| (v, 1.0))
            .collect();
        let before: Vec<Vec3> = selection
            .iter()
            .map(|&(v, _)| mesh.positions()[v as usize])
            .collect();
        let targets: Vec<Vec3> = before.iter().map(|p| *p + Vec3::Z * 0.2).collect();
        let mut target_of = vec![INVALID; mesh.vertex_count()];
        for (slot, &(v, _)) in selection.iter().enumerate() {
            target_of[v as usize] = slot as u32;
        }
        let mut region = Region::default();
        region.size_for(&mesh);
        region.gather(&state, &mesh, &selection, &targets, &target_of);
        let mut moved = mesh.clone();
        for (&(v, _), &q) in selection.iter().zip(&targets) {
            moved.positions_mut()[v as usize] = q;
        }
        let skip = alone_in_region(&state, &region, &moved, (&selection, &before), 0.2);
        let faces = region.faces_around_once(&moved, selection.iter().map(|&(v, _)| v));
        let round = other_layers_near(&state, &region, &moved, &faces, 0.2);
        (skip, round.map(|near| near.vertices.len()))
    }

    /// The skip is taken only where the round would have found no vertex of another layer in
    /// a region that holds its query, and it is taken once the other sheet is out of reach.
    #[test]
    fn the_first_round_is_skipped_only_where_it_would_find_nothing() {
        let (mut skipped, mut searched) = (0, 0);
        for tenth in 5..80 {
            let (skip, round) = skip_and_round(tenth as f32 / 10.0);
            if skip {
                assert_eq!(round, Some(0), "gap {}", tenth as f32 / 10.0);
                skipped += 1;
            } else {
                searched += 1;
            }
        }
        assert!(
            skipped > 10 && searched > 10,
            "{skipped} skipped, {searched} searched"
        );
    }
}
