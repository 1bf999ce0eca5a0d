//! sLayer's collision response on the CPU: every moving vertex tested at its target against
//! the faces near its move and pulled back along it to the collision distance (the proximity
//! clamp, [`clamp_moves`] over [`pull_back`]), then the gap guard for moving faces against still
//! vertices (`super::gap_guard`), then the exact backstop (`super::backstop`).
//! [`collide_with`] runs the two with the first phase given, which is where a GPU backend
//! plugs in its own proximity passes.
//!
//! Each function runs in parallel (rayon) or sequentially, through the grids or by scanning
//! everything; all give bit-identical results, because every per-vertex result depends only on
//! the state before the pass and reductions are taken in a fixed order.

use glam::Vec3;

use super::backstop::{Backstop, undo_crossings};
use super::gap_guard::undo_gap_violations;
use super::neighbourhood::{in_ring, ring_vertices};
use super::region::{Region, Scratch, StepMoves, map_with_scratch, triangle};
use super::sheet::clear_around;
use super::state::StrokeState;
// The slack a vertex already within the collision distance is allowed (see its doc): the GPU's
// `wgsl/proximity.wgsl` has the same.
use crate::abi::CLAMP_SLACK;
use crate::geom::{Aabb, closest_point_on_triangle};
use crate::mesh::Mesh;

/// Bisection rounds when clamping a move: 2⁻¹⁶ of a step.
const CLAMP_ROUNDS: u32 = 16;

/// Tests one moving vertex, now at its tentative position, against the faces near its move
/// (only those in `changed`, if given). Returns the position it must be pulled back to, if any.
/// Public as the reference for the GPU kernel `proximity` (`tests/gpu_parity/proximity.rs`).
pub fn pull_back(
    state: &StrokeState<'_>,
    region: &Region,
    mesh: &Mesh,
    v: u32,
    start: Vec3,
    changed: Option<&[bool]>,
    scratch: &mut Scratch,
) -> Option<Vec3> {
    let d = state.collision_distance;
    let x = mesh.positions()[v as usize];
    let query = Aabb::of_points(&[start, x]).expanded(d);
    let own_layer = mesh.vertex_layers()[v as usize];
    let layers = mesh.face_layers();
    // Within a clear sheet nothing outside the ring is within d (`super::sheet`).
    let own_clear = region.is_clear(own_layer);
    if own_clear && region.single_layer() {
        return None;
    }
    let kept_ring = region.rings.get(mesh, v, state.ring);
    let mut ring_ready = false;
    let mut ring = std::mem::take(&mut scratch.ring);
    let mut nearby = std::mem::take(&mut scratch.nearby);
    nearby.clear();
    let gather = |local| nearby.push(local as u32);
    // A clear layer's own faces are skipped below: they are not even listed.
    let skip = own_clear.then_some(own_layer);
    match changed {
        // Only the faces the last pass changed are tested: those filed apart, if they are.
        Some(_) => region.changed_candidates((&query, skip), scratch, gather),
        None => region.candidates((&query, skip), scratch, gather),
    }
    let mut t = 1.0f32;
    for &local in &nearby {
        if changed.is_some_and(|marks| !marks[local as usize]) {
            continue;
        }
        let f = region.faces[local as usize];
        let tri = mesh.faces()[f as usize];
        if tri.contains(&v) || !region.boxes[local as usize].within(x, d) {
            continue;
        }
        // The vertex's own neighbourhood is near by construction, not by collision.
        if layers[f as usize] == own_layer {
            if own_clear {
                continue;
            }
            if kept_ring.is_none() && !ring_ready {
                ring_vertices(mesh, v, state.ring, &mut ring);
                ring_ready = true;
            }
            let own_ring = kept_ring.unwrap_or(&ring);
            if tri.iter().any(|&u| in_ring(own_ring, u)) {
                continue;
            }
        }
        let [a, b, c] = triangle(mesh, f);
        let distance = |y: Vec3| closest_point_on_triangle(y, a, b, c).distance(y);
        let here = distance(x);
        if here >= d {
            continue;
        }
        // Never closer than the collision distance, nor closer than it already was (give or
        // take the slack).
        let threshold = d.min(distance(start));
        if here >= threshold - CLAMP_SLACK * d {
            continue;
        }
        // Distance along the move is convex and safe at its start: bisect for the last safe
        // fraction, always over the whole move so that the result does not depend on the
        // order faces are met in.
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        for _ in 0..CLAMP_ROUNDS {
            let mid = 0.5 * (lo + hi);
            if distance(start + (x - start) * mid) >= threshold {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        t = t.min(lo);
    }
    scratch.ring = ring;
    scratch.nearby = nearby;
    (t < 1.0).then(|| start + (x - start) * t)
}

/// The `moving` vertices (indices into `selection`) less those their own neighbourhood
/// clears, in a region of one layer that is a sheet but not clear as a whole
/// (`super::sheet::clear_around`): those need no search. Worth its walk where it spares a
/// whole search, on the first pass; later passes test most vertices against the few faces
/// the last one changed.
fn without_cleared(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &Mesh,
    selection: &[(u32, f32)],
    moving: Vec<usize>,
) -> Vec<usize> {
    let Some(&first) = moving.first().filter(|_| region.single_layer()) else {
        return moving;
    };
    let layer = mesh.vertex_layers()[selection[first].0 as usize];
    let Some(&sheet) = region.sheet(layer).filter(|sheet| !sheet.clear) else {
        return moving;
    };
    let view: &Region = region;
    let d = state.collision_distance;
    let cleared = map_with_scratch(state.parallel, &moving, |scratch, &i| {
        let v = selection[i].0;
        let ring = match view.rings.get(mesh, v, state.ring) {
            Some(kept) => kept,
            None => {
                ring_vertices(mesh, v, state.ring, &mut scratch.ring);
                &scratch.ring
            }
        };
        clear_around(mesh, view, &sheet, (v, ring, state.ring), d)
    });
    region.cleared_vertices += cleared.iter().filter(|&&c| c).count();
    let kept = moving.into_iter().zip(cleared).filter(|&(_, c)| !c);
    kept.map(|(i, _)| i).collect()
}

/// What the collision phase did.
#[derive(Debug, Default)]
pub struct CollisionOutcome {
    /// Final positions, one per selected vertex.
    pub positions: Vec<Vec3>,
    pub clamped: usize,
    pub reverted: usize,
    /// Searches within a layer were skipped: it was a sheet in the step's region.
    pub culled: bool,
    /// Moving vertices the clamp's first pass did not search, their own neighbourhood clearing
    /// them where their layer, alone in the region, is a sheet not clear as a whole
    /// (`super::sheet::clear_around`).
    pub culled_vertices: usize,
}

/// Passes of the proximity test before giving up on converging (each pass only re-tests against
/// faces that the previous one changed; two passes are the rule).
pub const MAX_PASSES: usize = 8;

/// Proximity test and clamping (sLayer's narrow phase and response), then the exact backstop.
/// Leaves the final positions in `mesh`.
///
/// Every moving vertex is tested at its target against the faces at *their* targets — the state
/// the step is heading for — not against where they were: a patch carried by grab or turned by
/// twist then never collides with its own old position, and two active layers moving together
/// keep their gap instead of colliding with each other's past. A vertex closer than the
/// collision distance `d` to a face outside its neighbourhood is pulled back along its own move
/// to the last point at distance `min(d, distance from its start)`. Pulling some vertices back
/// moves their faces, so the test repeats against the faces that changed, all vertices of a
/// pass deciding from the same state (Jacobi), which keeps the result independent of thread
/// count and search order.
pub fn collide(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    selection: &[(u32, f32)],
    targets: &[Vec3],
    target_of: &[u32],
) -> CollisionOutcome {
    let moves = (selection, targets, target_of);
    collide_with(state, region, mesh, moves, |region, mesh, before| {
        clamp_in_region(state, region, mesh, moves, before)
    })
}

/// [`collide`] with its first phase — targets written in, proximity passes — done by `clamp`
/// (given the region, the mesh and each selected vertex's start), which must leave the
/// positions [`clamp_moves`] would, and say what it leaves the backstop: a GPU backend runs
/// it there, and filters the backstop's first round too.
pub fn collide_with(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    moves: StepMoves<'_>,
    clamp: impl FnOnce(&mut Region, &mut Mesh, &[Vec3]) -> Backstop,
) -> CollisionOutcome {
    let (selection, targets, _) = moves;
    let before: Vec<Vec3> = selection
        .iter()
        .map(|&(v, _)| mesh.positions()[v as usize])
        .collect();
    region.forget();
    let backstop = clamp(region, mesh, &before);
    let culled = region.found_a_sheet();
    let clamped_count = selection
        .iter()
        .zip(targets)
        .filter(|((v, _), q)| mesh.positions()[*v as usize] != **q)
        .count();

    // The gap guard and the backstop each undo moves, which can void what the other found
    // clean: they take turns until the backstop undoes nothing (each move is undone at most
    // once, so this ends).
    let mut reverted = 0;
    let mut backstop = Some(backstop);
    loop {
        let kept_apart = undo_gap_violations(state, region, mesh, moves, &before);
        if kept_apart > 0 {
            region.positions_changed();
        }
        // Pairs a GPU filtered were filtered before those moves were undone: search instead.
        let next = match backstop.take() {
            Some(Backstop::Undecided(_)) if kept_apart > 0 => Backstop::Gather,
            Some(first) => first,
            None => Backstop::Search,
        };
        let uncrossed = undo_crossings(state, region, mesh, moves, &before, next);
        reverted += kept_apart + uncrossed;
        if uncrossed == 0 {
            break;
        }
    }
    region.step_ended(mesh);
    let positions = selection
        .iter()
        .map(|&(v, _)| mesh.positions()[v as usize])
        .collect();
    CollisionOutcome {
        positions,
        clamped: clamped_count,
        reverted,
        culled,
        culled_vertices: region.cleared_vertices,
    }
}

/// The CPU's first phase: the region gathered, then [`clamp_moves`].
pub fn clamp_in_region(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    (selection, targets, target_of): StepMoves<'_>,
    before: &[Vec3],
) -> Backstop {
    region.gather_unfiled(state, mesh, selection, targets);
    clamp_moves(state, region, mesh, (selection, targets, target_of), before);
    Backstop::Search
}

/// The first phase of a step whose region is one layer, a clear sheet where the moves end
/// (`super::sheet`): the targets placed and nothing pulled back, which is what
/// [`clamp_moves`] leaves there (each [`pull_back`] finds nothing), at the cost of the
/// region's gathering and the sheet test alone. Returns whether it was so; if not, the
/// selection is back at `before` (the positions' version too: nothing moved) and the region
/// gathered for the passes to run elsewhere.
/// For backends whose proximity passes run off the CPU (the GPU's): they skip them where the
/// CPU's would have skipped every search.
pub fn clamp_on_a_clear_sheet(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    (selection, targets, _): StepMoves<'_>,
    before: &[Vec3],
) -> bool {
    if !state.cull || selection.is_empty() {
        return false;
    }
    region.gather_unfiled(state, mesh, selection, targets);
    let stamp = mesh.version().positions;
    place(mesh, selection, targets);
    if is_a_clear_sheet_alone(state, region, mesh) {
        return true;
    }
    let starts = selection
        .iter()
        .map(|&(v, _)| v)
        .zip(before.iter().copied());
    mesh.put_back_positions(starts, stamp);
    region.positions_changed();
    false
}

/// Whether the step's region, gathered around the selection where it is now and its
/// `targets`, is one layer and a clear sheet where the mesh is now; the region is left
/// ungathered. For a backend that ran the passes elsewhere to guess whether the next step's
/// may be skipped ([`clamp_on_a_clear_sheet`]).
pub fn lies_on_a_clear_sheet(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &Mesh,
    (selection, targets): (&[(u32, f32)], &[Vec3]),
) -> bool {
    if !state.cull || selection.is_empty() {
        return false;
    }
    region.gather_unfiled(state, mesh, selection, targets);
    let clear = is_a_clear_sheet_alone(state, region, mesh);
    region.forget();
    clear
}

/// Whether the gathered region is one layer, a clear sheet where the mesh is now.
fn is_a_clear_sheet_alone(state: &StrokeState<'_>, region: &mut Region, mesh: &Mesh) -> bool {
    region.positions_changed();
    region.find_sheets(state, mesh);
    !region.worth_searching_near()
}

/// Writes `at` as the positions of the `selection`'s vertices.
fn place(mesh: &mut Mesh, selection: &[(u32, f32)], at: &[Vec3]) {
    let positions = mesh.positions_mut();
    for (&(v, _), &p) in selection.iter().zip(at) {
        positions[v as usize] = p;
    }
}

/// The first phase of [`collide`] (sLayer's narrow phase and response): the selection moved to
/// its targets, then Jacobi passes of [`pull_back`] until none pulls a vertex back. `before`
/// holds each selected vertex's start; the positions are left in `mesh`.
pub fn clamp_moves(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    moves: StepMoves<'_>,
    before: &[Vec3],
) {
    let (selection, targets, _) = moves;
    place(mesh, selection, targets);
    region.positions_changed();
    region.forget_changed();

    // Per local face: changed by the last pass (the first pass tests every face).
    let mut changed: Option<Vec<bool>> = None;
    // Per selected vertex: pulled back by the last pass. Such a vertex is tested against every
    // face again: distance along a move is convex, so a point short of the target can be
    // nearer a face than both ends were (the move passed by it), and that face has not changed.
    let mut pulled_last = vec![false; selection.len()];
    for pass in 0..MAX_PASSES {
        let mut moving: Vec<usize> = (0..selection.len())
            .filter(|&i| mesh.positions()[selection[i].0 as usize] != before[i])
            .collect();
        region.find_sheets(state, mesh);
        // Vertices of a layer that is a clear sheet here skip their own layer: no ring.
        let unclear: Vec<u32> = (moving.iter().map(|&i| selection[i].0))
            .filter(|&v| !region.is_clear(mesh.vertex_layers()[v as usize]))
            .collect();
        region
            .rings
            .prepare(mesh, state.ring, &unclear, state.parallel);
        if pass == 0 {
            moving = without_cleared(state, region, mesh, selection, moving);
        }
        if region.worth_searching_near() && !moving.is_empty() {
            match pass {
                0 => region.file_faces_near(state, mesh, moves, (before, &moving)),
                _ => region.file_faces(mesh, moves, before),
            }
        }
        let region_view: &Region = region;
        let mesh_view: &Mesh = mesh;
        let changed_view = changed.as_deref();
        let pulled_view = &pulled_last;
        let pulled: Vec<Option<Vec3>> = map_with_scratch(state.parallel, &moving, |scratch, &i| {
            let faces = if pulled_view[i] { None } else { changed_view };
            pull_back(
                state,
                region_view,
                mesh_view,
                selection[i].0,
                before[i],
                faces,
                scratch,
            )
        });
        let last_pass = pass + 1 == MAX_PASSES;
        let mut moved_back = Vec::new();
        pulled_last.fill(false);
        {
            let positions = mesh.positions_mut();
            for (&i, x) in moving.iter().zip(pulled) {
                let Some(x) = x else { continue };
                let v = selection[i].0;
                // Out of passes: what still collides goes back to where it was.
                positions[v as usize] = if last_pass { before[i] } else { x };
                pulled_last[i] = true;
                moved_back.push(v);
            }
        }
        if moved_back.is_empty() {
            break;
        }
        // The faces the pass changed are filed apart from all the region's faces' boxes.
        region.file_the_rest(mesh, moves, before);
        region.positions_changed();
        let mut marks = vec![false; region.faces.len()];
        for &v in &moved_back {
            for f in mesh.faces_around(v) {
                if let Some(local) = region.local(f) {
                    marks[local] = true;
                }
            }
        }
        region.file_changed(&marks);
        changed = Some(marks);
    }
}
