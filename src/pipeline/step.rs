//! One step of Algorithm 2 on the CPU: select, deform, collide. Each function is written once and
//! runs either in parallel (rayon) or sequentially, and either through the grids or by scanning
//! everything (the reference); all four combinations give bit-identical results, because every
//! per-vertex result depends only on the state before the step and reductions are taken in a
//! fixed order.

use glam::Vec3;
use rayon::prelude::*;

use crate::brush::{Dab, displacement};
use crate::collide::LocalFaceGrid;
use crate::collide::neighbourhood::ring_vertices;
use crate::geom::{Aabb, closest_point_on_triangle, triangles_intersect};
use crate::grid::SpatialHash;
use crate::mesh::{INVALID, LayerId, Mesh, VertexFlags};

/// Bisection rounds when clamping a move: 2⁻¹⁶ of a step.
const CLAMP_ROUNDS: u32 = 16;

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

/// Per-thread scratch: a stamp per face for de-duplication.
pub struct Scratch {
    stamp: Vec<u32>,
    generation: u32,
    ring: Vec<u32>,
    nearby: Vec<u32>,
}

impl Scratch {
    pub fn new(faces: usize) -> Scratch {
        Scratch {
            stamp: vec![0; faces],
            generation: 0,
            ring: Vec::new(),
            nearby: Vec::new(),
        }
    }

    fn next_generation(&mut self, faces: usize) -> u32 {
        if self.stamp.len() < faces {
            self.stamp.resize(faces, 0);
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.generation = 1;
        }
        self.generation
    }
}

/// Maps `f` over `items`, in parallel or not, with per-thread scratch.
fn map_with_scratch<T: Send, I: Sync>(
    parallel: bool,
    faces: usize,
    items: &[I],
    f: impl Fn(&mut Scratch, &I) -> T + Sync + Send,
) -> Vec<T> {
    if parallel {
        items
            .par_iter()
            .map_init(|| Scratch::new(faces), |s, item| f(s, item))
            .collect()
    } else {
        let mut scratch = Scratch::new(faces);
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
    /// Per mesh face: the generation that last put it in `faces`.
    face_stamp: Vec<u32>,
    generation: u32,
}

impl Region {
    fn gather(
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
        if self.face_stamp.len() < mesh.face_count() {
            self.face_stamp.resize(mesh.face_count(), 0);
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.face_stamp.fill(0);
            self.generation = 1;
        }
        self.faces.clear();
        for &v in &self.vertices {
            for f in mesh.faces_around(v) {
                let stamp = &mut self.face_stamp[f as usize];
                if *stamp != self.generation {
                    *stamp = self.generation;
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

    /// Local faces whose box overlaps `query`, each once.
    fn candidates(&self, query: &Aabb, scratch: &mut Scratch, mut f: impl FnMut(usize)) {
        if self.use_grid {
            let generation = scratch.next_generation(self.faces.len());
            self.grid.for_each_candidate(query, |local| {
                let slot = &mut scratch.stamp[local as usize];
                if *slot != generation {
                    *slot = generation;
                    if self.boxes[local as usize].overlaps(query) {
                        f(local as usize);
                    }
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

fn triangle(mesh: &Mesh, f: u32) -> [Vec3; 3] {
    mesh.face_positions(f as usize)
}

/// What the collision phase did.
#[derive(Debug, Default)]
pub struct CollisionOutcome {
    /// Final positions, one per selected vertex.
    pub positions: Vec<Vec3>,
    pub clamped: usize,
    pub reverted: usize,
}

/// Proximity test and clamping of every move against the state before the step (sLayer's
/// narrow phase), then the exact backstop. Leaves the final positions in `mesh`.
pub fn collide(
    state: &StrokeState<'_>,
    region: &mut Region,
    mesh: &mut Mesh,
    selection: &[(u32, f32)],
    targets: &[Vec3],
    target_of: &[u32],
) -> CollisionOutcome {
    region.gather(state, mesh, selection, targets, target_of);
    let region: &Region = region;
    let d = state.collision_distance;
    let layers: &[LayerId] = mesh.face_layers();
    let before: Vec<Vec3> = selection
        .iter()
        .map(|&(v, _)| mesh.positions()[v as usize])
        .collect();

    // Phase A: each vertex against the faces as they were before the step.
    let mesh_view: &Mesh = mesh;
    let clamped: Vec<(Vec3, bool)> = map_with_scratch(
        state.parallel,
        region.faces.len(),
        &(0..selection.len()).collect::<Vec<_>>(),
        |scratch, &i| {
            let v = selection[i].0;
            let (p, q) = (before[i], targets[i]);
            if p == q {
                return (q, false);
            }
            let query = Aabb::of_points(&[p, q]).expanded(d);
            let own_layer = mesh_view.vertex_layers()[v as usize];
            let mut ring_ready = false;
            let mut ring = std::mem::take(&mut scratch.ring);
            let mut t = 1.0f32;
            let mut nearby = std::mem::take(&mut scratch.nearby);
            nearby.clear();
            region.candidates(&query, scratch, |local| nearby.push(local as u32));
            for &local in &nearby {
                let f = region.faces[local as usize];
                let tri = mesh_view.faces()[f as usize];
                if tri.contains(&v) {
                    continue;
                }
                if !region.boxes[local as usize].within(q, d) {
                    continue;
                }
                // The vertex's own neighbourhood is near by construction, not by collision.
                if layers[f as usize] == own_layer {
                    if !ring_ready {
                        ring_vertices(mesh_view, v, state.ring, &mut ring);
                        ring_ready = true;
                    }
                    if tri.iter().any(|u| ring.contains(u)) {
                        continue;
                    }
                }
                let [a, b, c] = triangle(mesh_view, f);
                let dq = closest_point_on_triangle(q, a, b, c).distance(q);
                if dq >= d {
                    continue;
                }
                let dp = closest_point_on_triangle(p, a, b, c).distance(p);
                let threshold = d.min(dp);
                if dq >= threshold {
                    continue;
                }
                // Distance along the move is convex: bisect for the last safe fraction.
                // Always over the whole move, so the result for a face does not depend on
                // the order faces are met in (the grid and the reference meet them differently).
                let (mut lo, mut hi) = (0.0f32, 1.0f32);
                let at = |s: f32| {
                    let x = p + (q - p) * s;
                    closest_point_on_triangle(x, a, b, c).distance(x)
                };
                for _ in 0..CLAMP_ROUNDS {
                    let mid = 0.5 * (lo + hi);
                    if at(mid) >= threshold {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                t = t.min(lo);
            }
            scratch.ring = ring;
            scratch.nearby = nearby;
            if t < 1.0 {
                (p + (q - p) * t, true)
            } else {
                (q, false)
            }
        },
    );
    let clamped_count = clamped.iter().filter(|c| c.1).count();
    {
        let positions = mesh.positions_mut();
        for (&(v, _), &(x, _)) in selection.iter().zip(&clamped) {
            positions[v as usize] = x;
        }
    }

    // Phase B: undo moves until no moved face crosses any face (edge–edge crossings and a
    // still vertex poking through a moving face are invisible to phase A).
    let mut still_moved: Vec<bool> = clamped
        .iter()
        .zip(&before)
        .map(|(c, p)| c.0 != *p)
        .collect();
    let mut reverted = 0;
    loop {
        let mut moving_faces: Vec<u32> = selection
            .iter()
            .zip(&still_moved)
            .filter(|(_, m)| **m)
            .flat_map(|(&(v, _), _)| mesh.faces_around(v))
            .collect();
        moving_faces.sort_unstable();
        moving_faces.dedup();
        if moving_faces.is_empty() {
            break;
        }
        let is_moving = |f: u32| moving_faces.binary_search(&f).is_ok();
        let mesh_view: &Mesh = mesh;
        let crossings: Vec<Vec<(u32, u32)>> = map_with_scratch(
            state.parallel,
            region.faces.len(),
            &moving_faces,
            |scratch, &f| {
                let tri_f = triangle(mesh_view, f);
                let box_f = Aabb::of_points(&tri_f);
                let faces = mesh_view.faces();
                let mut found = Vec::new();
                region.candidates(&box_f, scratch, |local| {
                    let g = region.faces[local];
                    if g == f || (g < f && is_moving(g)) {
                        return;
                    }
                    if faces[g as usize]
                        .iter()
                        .any(|v| faces[f as usize].contains(v))
                    {
                        return;
                    }
                    let tri_g = triangle(mesh_view, g);
                    if !box_f.overlaps(&Aabb::of_points(&tri_g)) {
                        return;
                    }
                    if triangles_intersect(tri_f, tri_g) {
                        found.push((f.min(g), f.max(g)));
                    }
                });
                found
            },
        );
        let mut pairs: Vec<(u32, u32)> = crossings.into_iter().flatten().collect();
        if pairs.is_empty() {
            break;
        }
        pairs.sort_unstable();
        let mut undo: Vec<u32> = Vec::new();
        for (f, g) in pairs {
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
        for v in undo {
            positions[v as usize] = before[target_of[v as usize] as usize];
        }
        reverted += undone;
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
