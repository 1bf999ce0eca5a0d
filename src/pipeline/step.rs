//! One step of Algorithm 2 on the CPU: select, deform, collide. Each function is written once and
//! runs either in parallel (rayon) or sequentially, and either through the grids or by scanning
//! everything (the reference); all four combinations give bit-identical results, because every
//! per-vertex result depends only on the state before the step and reductions are taken in a
//! fixed order.

use glam::Vec3;
use rayon::prelude::*;

use crate::brush::{Dab, DabFrame, Paint, displacement, paint_share};
use crate::collide::neighbourhood::ring_vertices;
use crate::collide::{LocalFaceGrid, Stamps};
use crate::cpu;
use crate::geom::{Aabb, closest_point_on_triangle, neighbours_overlap, triangles_intersect};
use crate::gpu::{SelectedVertex, frame_params};
use crate::grid::SpatialHash;
use crate::mesh::{Brdf, INVALID, Mesh, VertexFlags};

/// Bisection rounds when clamping a move: 2⁻¹⁶ of a step.
const CLAMP_ROUNDS: u32 = 16;

/// The brush frame of `probe` (its centre, radius and motion) over `selection`: the falloff-
/// weighted normal (unless the sample brings its own `normal`) and centroid under the brush.
/// Summed in fixed point (`crate::cpu::brush_frame`, the mirror of `wgsl/brush_frame.wgsl`) so
/// that every backend gets the same bits, whatever order its selection came in.
pub fn brush_frame(
    mesh: &Mesh,
    selection: &[(u32, f32)],
    probe: &Dab,
    normal: Option<Vec3>,
) -> DabFrame {
    let selected: Vec<SelectedVertex> = selection
        .iter()
        .map(|&(vertex, weight)| SelectedVertex { vertex, weight })
        .collect();
    let mut sums = [0u32; cpu::FRAME_SUM_WORDS];
    cpu::brush_frame(
        &frame_params(probe.frame.center, probe.brush.radius, selected.len()),
        &cpu::FrameInputs {
            positions: mesh.positions(),
            normals: mesh.normals(),
            selected: &selected,
            selection_count: selected.len() as u32,
        },
        &mut sums,
    );
    frame_of_sums(&sums, probe, normal)
}

/// Which parts of the frame come from the sums: the plane point always, the normal unless the
/// sample brings its own (`DeformParams::frame`).
pub fn frame_flags(normal: Option<Vec3>) -> u32 {
    cpu::FRAME_PLANE_FROM_SUMS
        | if normal.is_none() {
            cpu::FRAME_NORMAL_FROM_SUMS
        } else {
            0
        }
}

/// The frame from `brush_frame`'s sums, as `wgsl/deform.wgsl` resolves it: +Z where the
/// normals under the brush cancel out, the centre where nothing is under it.
pub fn frame_of_sums(sums: &cpu::FrameSums, probe: &Dab, normal: Option<Vec3>) -> DabFrame {
    let center = probe.frame.center;
    let (normal, plane_point) = cpu::frame_from_sums(
        sums,
        frame_flags(normal),
        (center, probe.brush.radius),
        (normal.unwrap_or(Vec3::Z), center),
    );
    DabFrame {
        center,
        normal,
        plane_point,
        motion: probe.frame.motion,
    }
}

/// Steps per sample are capped: a sample asking for more is a runaway brush, and moves farther
/// than this many steps of `max_step` in this many.
pub const MAX_STEPS_PER_SAMPLE: usize = 256;

/// The steps a sample whose longest move is `longest_move` takes, each of at most
/// `step_limit` (Algorithm 2 splits a motion so that no step crosses a layer).
pub fn steps_for(longest_move: f32, step_limit: f32) -> usize {
    ((longest_move / step_limit).ceil() as usize).clamp(1, MAX_STEPS_PER_SAMPLE)
}

/// The longest move from each selected vertex's position in `mesh` to its target.
pub fn longest_move(mesh: &Mesh, selection: &[(u32, f32)], targets: &[Vec3]) -> f32 {
    selection
        .iter()
        .zip(targets)
        .map(|(&(v, _), q)| mesh.positions()[v as usize].distance(*q))
        .fold(0.0f32, f32::max)
}

/// A vertex already within the collision distance of a face is pulled back when its move
/// takes it closer by more than this share of the distance. A move along the face (a grab
/// carrying a patch over another layer) keeps the distance in exact arithmetic, and in floats
/// changes it by rounding only; without the slack, whether such a vertex is stopped would
/// depend on the last bits of the arithmetic, which differ between the CPU and a GPU (fused
/// multiply-adds), and the stop moves it by a whole step. `wgsl/proximity.wgsl` has the same.
pub use crate::abi::CLAMP_SLACK;

/// Everything a step reads that lasts for the whole stroke.
pub struct StrokeState<'a> {
    pub grid: Option<&'a SpatialHash>,
    pub active: &'a [bool],
    pub parallel: bool,
    /// Collision distance (world units).
    pub collision_distance: f32,
    /// Graph distance of the neighbourhood a vertex skips in its own layer.
    pub ring: u32,
    /// An upper bound on every edge length right now.
    pub max_edge: f32,
}

/// Per-thread scratch: the faces a query has met, a ring, a candidate list.
#[derive(Default)]
pub struct Scratch {
    seen: Stamps,
    ring: Vec<u32>,
    nearby: Vec<u32>,
}

/// Maps `f` over `items`, in parallel or not, with per-thread scratch.
fn map_with_scratch<T: Send, I: Sync>(
    parallel: bool,
    items: &[I],
    f: impl Fn(&mut Scratch, &I) -> T + Sync + Send,
) -> Vec<T> {
    if parallel {
        items
            .par_iter()
            .map_init(Scratch::default, |s, item| f(s, item))
            .collect()
    } else {
        let mut scratch = Scratch::default();
        items.iter().map(|item| f(&mut scratch, item)).collect()
    }
}

/// Brush selection: active, unmasked vertices with positive falloff weight, sorted by index.
pub fn select(state: &StrokeState<'_>, mesh: &Mesh, dab: &Dab) -> Vec<(u32, f32)> {
    let brush = &dab.brush;
    let center = dab.frame.center;
    let mut found = Vec::new();
    match state.grid {
        Some(grid) => grid.vertices_in_sphere(mesh.positions(), center, brush.radius, &mut found),
        None => {
            let r2 = brush.radius * brush.radius;
            found.extend(
                mesh.positions()
                    .iter()
                    .enumerate()
                    .filter(|(v, p)| {
                        mesh.adjacency().vertex_corner[*v] != INVALID
                            && p.distance_squared(center) <= r2
                    })
                    .map(|(v, _)| v as u32),
            );
        }
    }
    found.sort_unstable();
    found
        .into_iter()
        .filter(|&v| selectable(state, mesh, v))
        .filter_map(|v| {
            let t = mesh.positions()[v as usize].distance(center) / brush.radius;
            let w = brush.falloff.weight(t);
            (w > 0.0).then_some((v, w))
        })
        .collect()
}

/// On an active layer, not masked, alive.
pub fn selectable(state: &StrokeState<'_>, mesh: &Mesh, v: u32) -> bool {
    let flags = mesh.flags()[v as usize];
    state.active[mesh.vertex_layers()[v as usize] as usize]
        && !flags.intersects(VertexFlags::MASKED | VertexFlags::DEAD)
}

/// Centroid of a vertex's one-ring; on a boundary, of its two boundary neighbours, so open
/// sheets do not shrink from their rims.
fn ring_centroid(mesh: &Mesh, v: u32) -> Vec3 {
    let positions = mesh.positions();
    if mesh.is_boundary_vertex(v) {
        let ring = mesh.neighbours(v);
        let (first, last) = (ring[0], ring[ring.len() - 1]);
        return 0.5 * (positions[first as usize] + positions[last as usize]);
    }
    let mut sum = Vec3::ZERO;
    let mut count = 0.0;
    for c in mesh.adjacency().corners_around(v) {
        sum += positions[mesh.corner_vertex(crate::mesh::next(c)) as usize];
        count += 1.0;
    }
    if count > 0.0 {
        sum / count
    } else {
        positions[v as usize]
    }
}

/// Target positions of the selected vertices. Non-finite results (absurd input) stay put.
pub fn deform(
    state: &StrokeState<'_>,
    mesh: &Mesh,
    dab: &Dab,
    selection: &[(u32, f32)],
) -> Vec<Vec3> {
    let needs_ring = dab.brush.kind == crate::brush::BrushKind::Smooth;
    let target = |&(v, w): &(u32, f32)| {
        let p = mesh.positions()[v as usize];
        let centroid = if needs_ring {
            ring_centroid(mesh, v)
        } else {
            p
        };
        let q = p + displacement(dab, p, mesh.normals()[v as usize], centroid, w);
        if q.is_finite() { q } else { p }
    };
    if state.parallel {
        selection.par_iter().map(target).collect()
    } else {
        selection.iter().map(target).collect()
    }
}

/// Painted BRDFs of the selected vertices (sLayer's reflectance editing): each becomes a
/// weighted sum of its own BRDF and the brush's at its position, the weight being its falloff
/// weight × pressure × opacity. Selection already leaves out inactive layers and masked
/// vertices, so those keep their BRDF.
pub fn paint(
    state: &StrokeState<'_>,
    mesh: &Mesh,
    dab: &Dab,
    selection: &[(u32, f32)],
    paint: &Paint,
) -> Vec<Brdf> {
    let normal = dab.frame.normal;
    let painted = |&(v, w): &(u32, f32)| {
        let own = mesh.brdfs()[v as usize];
        let brush = paint.brdf_at(mesh.positions()[v as usize], normal);
        own.lerp(&brush, paint_share(w, dab.pressure, paint.opacity))
    };
    if state.parallel {
        selection.par_iter().map(painted).collect()
    } else {
        selection.iter().map(painted).collect()
    }
}

/// The faces around one step: everything that could come within the collision distance of a
/// moving vertex, or cross a moving face. Kept in the pipeline between steps so its buffers are
/// reused.
#[derive(Default)]
pub struct Region {
    faces: Vec<u32>,
    /// Per local face: box of its old and target positions.
    boxes: Vec<Aabb>,
    grid: LocalFaceGrid,
    use_grid: bool,
    vertices: Vec<u32>,
    /// Mesh faces already in `faces`, and their index there.
    gathered: Stamps,
    local_index: Vec<u32>,
}

impl Region {
    /// Collects the faces around the step's moves (public so that `tests/gpu_parity.rs` can
    /// check the GPU proximity mirror against [`pull_back`]).
    pub fn gather(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        selection: &[(u32, f32)],
        targets: &[Vec3],
        target_of: &[u32],
    ) {
        let positions = mesh.positions();
        let mut bounds = Aabb::EMPTY;
        for (&(v, _), &q) in selection.iter().zip(targets) {
            bounds = bounds.including(positions[v as usize]).including(q);
        }
        // A face within d of a moving point has a vertex within d + longest edge; a face that
        // crosses a moving face has a vertex within two longest edges of the moving vertex.
        let reach = state.collision_distance + 2.0 * state.max_edge;
        let region = bounds.expanded(reach);
        self.vertices.clear();
        match state.grid {
            Some(grid) => {
                let vertices = &mut self.vertices;
                grid.for_each_in_box(region.min, region.max, |v| vertices.push(v));
            }
            None => self
                .vertices
                .extend((0..mesh.vertex_count() as u32).filter(|&v| {
                    let p = positions[v as usize];
                    mesh.adjacency().vertex_corner[v as usize] != INVALID
                        && p.cmpge(region.min).all()
                        && p.cmple(region.max).all()
                })),
        }
        // Faces of those vertices, each once. Their order does not matter: every result below
        // is a minimum or a sorted set.
        self.gathered.start(mesh.face_count());
        self.local_index
            .resize(mesh.face_count().max(self.local_index.len()), 0);
        self.faces.clear();
        for &v in &self.vertices {
            for f in mesh.faces_around(v) {
                if self.gathered.insert(f as usize) {
                    self.local_index[f as usize] = self.faces.len() as u32;
                    self.faces.push(f);
                }
            }
        }
        self.boxes.clear();
        self.boxes.extend(self.faces.iter().map(|&f| {
            mesh.faces()[f as usize].iter().fold(Aabb::EMPTY, |b, &v| {
                let p = positions[v as usize];
                let slot = target_of[v as usize];
                let b = b.including(p);
                if slot == INVALID {
                    b
                } else {
                    b.including(targets[slot as usize])
                }
            })
        }));
        self.use_grid = state.grid.is_some();
        if let Some(g) = state.grid {
            self.grid
                .build(&self.boxes, region, LOCAL_CELL_EDGES * g.cell_size());
        }
    }

    /// Index of a mesh face in this region, if it is in it.
    fn local(&self, face: u32) -> Option<usize> {
        self.gathered
            .contains(face as usize)
            .then(|| self.local_index[face as usize] as usize)
    }

    /// Local faces whose box overlaps `query`, each once.
    fn candidates(&self, query: &Aabb, scratch: &mut Scratch, mut f: impl FnMut(usize)) {
        if self.use_grid {
            scratch.seen.start(self.faces.len());
            self.grid.for_each_candidate(query, |local| {
                if scratch.seen.insert(local as usize) && self.boxes[local as usize].overlaps(query)
                {
                    f(local as usize);
                }
            });
        } else {
            for (local, b) in self.boxes.iter().enumerate() {
                if b.overlaps(query) {
                    f(local);
                }
            }
        }
    }
}

/// Cell side of the per-step face grid, in edge lengths: a face box then covers one to two
/// cells per axis and a proximity query a handful.
const LOCAL_CELL_EDGES: f32 = 1.5;

fn face_normal(t: [Vec3; 3]) -> Vec3 {
    (t[1] - t[0]).cross(t[2] - t[0])
}

fn triangle(mesh: &Mesh, f: u32) -> [Vec3; 3] {
    mesh.face_positions(f as usize)
}

/// Tests one moving vertex, now at its tentative position, against the faces near its move
/// (only those in `changed`, if given). Returns the position it must be pulled back to, if any.
/// Public as the reference for the GPU kernel `proximity` (`tests/gpu_parity.rs`).
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
    let mut ring_ready = false;
    let mut ring = std::mem::take(&mut scratch.ring);
    let mut nearby = std::mem::take(&mut scratch.nearby);
    nearby.clear();
    region.candidates(&query, scratch, |local| nearby.push(local as u32));
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
            if !ring_ready {
                ring_vertices(mesh, v, state.ring, &mut ring);
                ring_ready = true;
            }
            if tri.iter().any(|u| ring.contains(u)) {
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

/// What the collision phase did.
#[derive(Debug, Default)]
pub struct CollisionOutcome {
    /// Final positions, one per selected vertex.
    pub positions: Vec<Vec3>,
    pub clamped: usize,
    pub reverted: usize,
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

/// A step's moves: the selection, each selected vertex's target, and per vertex its index in
/// the selection (`INVALID` for the others).
pub type StepMoves<'a> = (&'a [(u32, f32)], &'a [Vec3], &'a [u32]);

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

/// The CPU's first phase: the region gathered, then [`clamp_moves`].
pub fn clamp_in_region(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    (selection, targets, target_of): StepMoves<'_>,
    before: &[Vec3],
) -> Backstop {
    region.gather(state, mesh, selection, targets, target_of);
    clamp_moves(state, region, mesh, selection, targets, before);
    Backstop::Search
}

/// Gathers the region of a step whose selection has moved already: with the selection put
/// back at `before` meanwhile, so that it is the region [`clamp_in_region`] gathers.
fn gather_from_start(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    (selection, targets, target_of): StepMoves<'_>,
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
    region.gather(state, mesh, selection, targets, target_of);
    let positions = mesh.positions_mut();
    for (&(v, _), p) in selection.iter().zip(now) {
        positions[v as usize] = p;
    }
}

/// Whether face `f` turned over in the step: its normal before (vertices of the selection at
/// `before`, through `target_of`) and now point apart. A face turned over onto its neighbours
/// (a fold within a fan, which twist and pinch can make) shares vertices with everything it
/// overlaps, so no pair test sees it; its normal reversing does.
fn turned_over(mesh: &Mesh, f: u32, target_of: &[u32], before: &[Vec3]) -> bool {
    let old = mesh.faces()[f as usize].map(|w| {
        let slot = target_of[w as usize];
        if slot == INVALID {
            mesh.positions()[w as usize]
        } else {
            before[slot as usize]
        }
    });
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
    let (selection, targets, target_of) = moves;
    let before: Vec<Vec3> = selection
        .iter()
        .map(|&(v, _)| mesh.positions()[v as usize])
        .collect();
    let backstop = clamp(region, mesh, &before);
    let clamped_count = selection
        .iter()
        .zip(targets)
        .filter(|((v, _), q)| mesh.positions()[*v as usize] != **q)
        .count();

    // Phase B: undo moves until no moved face crosses any face (edge–edge crossings and a
    // still vertex poking through a moving face are invisible to phase A).
    let mut still_moved: Vec<bool> = selection
        .iter()
        .zip(&before)
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
    loop {
        let mut moving_faces: Vec<u32> =
            changed.iter().flat_map(|&v| mesh.faces_around(v)).collect();
        moving_faces.sort_unstable();
        moving_faces.dedup();
        if moving_faces.is_empty() {
            break;
        }
        let mut pairs: Vec<(u32, u32)> = match undecided.take() {
            // The filter tested exactly the pairs the search below would: the same crossings.
            Some(candidates) => candidates
                .into_iter()
                .map(|[f, g]| (f.min(g), f.max(g)))
                .filter(|&pair| pair_crosses(mesh, pair, target_of, &before))
                .collect(),
            None => {
                if !gathered {
                    gather_from_start(state, region, mesh, moves, &before);
                    gathered = true;
                }
                crossings(state, region, mesh, &moving_faces, (target_of, &before))
            }
        };
        if pairs.is_empty() {
            break;
        }
        pairs.sort_unstable();
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
        let undone = undo.len();
        let positions = mesh.positions_mut();
        for &v in &undo {
            positions[v as usize] = before[target_of[v as usize] as usize];
        }
        reverted += undone;
        changed = undo;
        if undone == 0 {
            // Crossings that involve no moving vertex were there before the step.
            break;
        }
    }
    let positions = selection
        .iter()
        .map(|&(v, _)| mesh.positions()[v as usize])
        .collect();
    CollisionOutcome {
        positions,
        clamped: clamped_count,
        reverted,
    }
}

/// The crossing pairs of `moving_faces` (ascending), searched in the gathered region: each
/// moving face against itself (turned over), the faces around its vertices (overlap beyond
/// a shared vertex) and the region's faces whose boxes meet its box. A pair of two moving
/// faces is tested from the lower one.
fn crossings(
    state: &StrokeState<'_>,
    region: &Region,
    mesh: &Mesh,
    moving_faces: &[u32],
    (target_of, before): (&[u32], &[Vec3]),
) -> Vec<(u32, u32)> {
    let is_moving = |f: u32| moving_faces.binary_search(&f).is_ok();
    let found: Vec<Vec<(u32, u32)>> =
        map_with_scratch(state.parallel, moving_faces, |scratch, &f| {
            let tri_f = triangle(mesh, f);
            let box_f = Aabb::of_points(&tri_f);
            let faces = mesh.faces();
            let mut found = Vec::new();
            if turned_over(mesh, f, target_of, before) {
                found.push((f, f));
            }
            // Nor may the step fold two faces around a shared vertex onto each other: they
            // overlap while sharing a vertex, which the pair test skips.
            let ids_f = faces[f as usize];
            for w in ids_f {
                for g in mesh.faces_around(w) {
                    if g == f || (g < f && is_moving(g)) {
                        continue;
                    }
                    let tri_g = triangle(mesh, g);
                    if neighbours_overlap(tri_f, ids_f, tri_g, faces[g as usize]) {
                        found.push((f.min(g), f.max(g)));
                    }
                }
            }
            region.candidates(&box_f, scratch, |local| {
                let g = region.faces[local];
                if g == f || (g < f && is_moving(g)) || share_a_vertex(mesh, f, g) {
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

/// The first phase of [`collide`] (sLayer's narrow phase and response): the selection moved to
/// its targets, then Jacobi passes of [`pull_back`] until none pulls a vertex back. `before`
/// holds each selected vertex's start; the positions are left in `mesh`.
pub fn clamp_moves(
    state: &StrokeState<'_>,
    region: &Region,
    mesh: &mut Mesh,
    selection: &[(u32, f32)],
    targets: &[Vec3],
    before: &[Vec3],
) {
    {
        let positions = mesh.positions_mut();
        for (&(v, _), &q) in selection.iter().zip(targets) {
            positions[v as usize] = q;
        }
    }

    // Per local face: changed by the last pass (the first pass tests every face).
    let mut changed: Option<Vec<bool>> = None;
    for pass in 0..MAX_PASSES {
        let moving: Vec<usize> = (0..selection.len())
            .filter(|&i| mesh.positions()[selection[i].0 as usize] != before[i])
            .collect();
        let mesh_view: &Mesh = mesh;
        let changed_view = changed.as_deref();
        let pulled: Vec<Option<Vec3>> = map_with_scratch(state.parallel, &moving, |scratch, &i| {
            pull_back(
                state,
                region,
                mesh_view,
                selection[i].0,
                before[i],
                changed_view,
                scratch,
            )
        });
        let last_pass = pass + 1 == MAX_PASSES;
        let mut moved_back = Vec::new();
        {
            let positions = mesh.positions_mut();
            for (&i, x) in moving.iter().zip(pulled) {
                let Some(x) = x else { continue };
                let v = selection[i].0;
                // Out of passes: what still collides goes back to where it was.
                positions[v as usize] = if last_pass { before[i] } else { x };
                moved_back.push(v);
            }
        }
        if moved_back.is_empty() {
            break;
        }
        let mut marks = vec![false; region.faces.len()];
        for &v in &moved_back {
            for f in mesh.faces_around(v) {
                if let Some(local) = region.local(f) {
                    marks[local] = true;
                }
            }
        }
        changed = Some(marks);
    }
}
