//! Cutting a layer along a stroke (sLayer, "Editing Tools": the cut "snaps the stroke to
//! existing triangle edges"): the stroke is projected onto the layer, edges it crosses far
//! from a vertex are split where it crosses them, the projected points are joined by shortest
//! paths of edges, and the surface is cut open along that path. A closed or rim-to-rim cut
//! detaches a piece; an open one makes a slit.
//!
//! The two sides of a cut would lie on each other, touching along the whole path (a
//! collision at distance 0 for every later stroke, and a crossing for the exact test), so the
//! cut is opened: every vertex it duplicated moves half the collision distance into its own
//! side, as far as its faces allow, and the band is remeshed to `L`.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::time::Instant;

use glam::Vec3;

use super::obstacles::Obstacles;
use super::select::check_layer;
use super::{ToolError, check_length};
use crate::geom::{Aabb, closest_on_segment};
use crate::grid::SpatialHash;
use crate::mesh::{LayerId, Mesh};
use crate::remesh::{RemeshSettings, remesh_region};

/// A stroke point is snapped to a vertex this close (× L); farther, the nearest edge of its
/// face is split under it.
const SNAP_SHARE: f32 = 0.4;
/// A shortest path between two snapped points may cost this many times their distance (plus
/// two edges) before the stroke is taken to have left the surface there.
const DETOUR: f32 = 3.0;
/// What straying from the stroke costs a path, per unit of distance, beside its length.
const STRAY_COST: f32 = 2.0;
/// Halvings of a vertex's opening move before it is left where it is.
const OPENING_TRIES: u32 = 4;

/// How to cut.
#[derive(Debug, Clone, PartialEq)]
pub struct CutSettings {
    /// The layers cut, each on its own.
    pub layers: Vec<LayerId>,
    /// The mesh's edge length `L`.
    pub edge: f32,
    /// The two sides are opened this far apart.
    pub collision_distance: f32,
    /// Stroke points farther than this from a layer do not cut it.
    pub reach: f32,
}

impl CutSettings {
    /// `layers` cut at the mesh's edge length, opened by one edge, stroke points up to four
    /// edges off the surface.
    pub fn for_mesh(mesh: &Mesh, layers: &[LayerId]) -> CutSettings {
        let edge = mesh.mean_edge_length();
        CutSettings {
            layers: layers.to_vec(),
            edge,
            collision_distance: edge,
            reach: 4.0 * edge,
        }
    }
}

/// What a cut did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct CutReport {
    /// Edges the cut runs along.
    pub path_edges: usize,
    /// Edges split so that the path follows the stroke.
    pub splits: usize,
    /// Vertices duplicated (one per extra side of a vertex on the cut).
    pub duplicated: usize,
    /// The farthest a vertex of the path lies from the stroke as projected onto the layer.
    pub farthest_from_stroke: f32,
    /// Connected components before and after.
    pub components_before: usize,
    pub components_after: usize,
    pub millis: f64,
}

/// Cuts each of `settings.layers` along `stroke`. Fails, leaving the mesh as it was, on bad
/// settings or a stroke that comes nowhere near the layers; a cut that the exact test would
/// find crossing anything is not made.
pub fn cut(
    mesh: &mut Mesh,
    stroke: &[Vec3],
    settings: &CutSettings,
) -> Result<CutReport, ToolError> {
    let started = Instant::now();
    check_settings(mesh, stroke, settings)?;
    let mut work = mesh.clone();
    let mut report = CutReport {
        components_before: work.components().count(),
        ..CutReport::default()
    };
    let points = resample(stroke, settings.edge / 4.0);
    for &layer in &settings.layers {
        cut_layer(&mut work, &points, layer, settings, &mut report);
    }
    if report.path_edges == 0 {
        return Err(ToolError::EmptySelection(
            "the stroke crosses no edge of the layers it was to cut (is it on them?)".into(),
        ));
    }
    // Everything the cut changed lies near the stroke: only faces there need the exact test.
    let crossings =
        crate::collide::find_intersections_in(&work, &near_stroke(&points, settings)).total();
    if crossings > 0 {
        return Err(ToolError::CutNotOpened { pairs: crossings });
    }
    report.components_after = work.components().count();
    *mesh = work;
    report.millis = started.elapsed().as_secs_f64() * 1e3;
    Ok(report)
}

fn check_settings(mesh: &Mesh, stroke: &[Vec3], settings: &CutSettings) -> Result<(), ToolError> {
    let extent = mesh.extent().unwrap_or(0.0);
    check_length("the edge length", settings.edge, extent)?;
    check_length(
        "the collision distance",
        settings.collision_distance,
        extent,
    )?;
    check_length("the reach", settings.reach, extent)?;
    for &layer in &settings.layers {
        check_layer(mesh, layer)?;
    }
    if stroke.len() < 2 || stroke.iter().any(|p| !p.is_finite()) {
        return Err(ToolError::EmptySelection(
            "a cut needs a stroke of at least two finite points".into(),
        ));
    }
    Ok(())
}

/// The polyline through `stroke` with points no farther apart than `spacing`.
fn resample(stroke: &[Vec3], spacing: f32) -> Vec<Vec3> {
    let mut points = vec![stroke[0]];
    for pair in stroke.windows(2) {
        let steps = ((pair[1] - pair[0]).length() / spacing)
            .ceil()
            .clamp(1.0, 1e5) as usize;
        points.extend((1..=steps).map(|k| pair[0].lerp(pair[1], k as f32 / steps as f32)));
    }
    points
}

/// Cuts one layer: project, split under the stroke, snap, join by shortest paths, cut open.
fn cut_layer(
    mesh: &mut Mesh,
    points: &[Vec3],
    layer: LayerId,
    settings: &CutSettings,
    report: &mut CutReport,
) {
    let region = Aabb::of_points(points).expanded(settings.reach + settings.edge);
    let obstacles = Obstacles::near(mesh, region, 1.5 * settings.edge);
    let nearest: Vec<Option<(u32, Vec3)>> = points
        .iter()
        .map(|&p| obstacles.nearest_face(p, settings.reach, layer))
        .collect();
    // A point off the layer's edge finds its nearest face on the rim, to one side of it: it
    // does not cut there. Over the surface, the nearest point lies straight under it.
    let projected: Vec<Option<(u32, Vec3)>> = points
        .iter()
        .zip(&nearest)
        .map(|(&p, hit)| {
            hit.filter(|&(face, q)| {
                let n = mesh.face_normal(face as usize);
                let d = p - q;
                (d - n * d.dot(n)).length() <= SNAP_SHARE * settings.edge
            })
        })
        .collect();
    let split_vertices = split_under(mesh, &projected, settings.edge, report);
    let mut snapped: Vec<Option<u32>> = projected
        .iter()
        .map(|hit| hit.map(|(face, q)| snap(mesh, face, q, &split_vertices)))
        .collect();
    // Where the stroke runs off the layer, the cut runs on to the rim vertex nearest to
    // where it left, so that a stroke across a piece detaches it.
    for i in 0..snapped.len() {
        let beside = |j: Option<usize>| {
            j.and_then(|j| projected.get(j))
                .is_some_and(Option::is_some)
        };
        if snapped[i].is_none() && (beside(i.checked_sub(1)) || beside(Some(i + 1))) {
            snapped[i] = nearest[i].and_then(|(face, q)| rim_vertex(mesh, face, q, settings.edge));
        }
    }
    let mut edges = Vec::new();
    for pair in snapped.windows(2) {
        let (Some(a), Some(b)) = (pair[0], pair[1]) else {
            continue;
        };
        if a == b {
            continue;
        }
        if mesh.find_edge(a, b).is_none() {
            split_between(mesh, a, b, report);
        }
        if let Some(path) = shortest_path(mesh, a, b, settings.edge) {
            edges.extend(path.windows(2).map(|w| [w[0], w[1]]));
        }
    }
    let stroke_on_layer: Vec<Vec3> = nearest.iter().flatten().map(|&(_, q)| q).collect();
    for v in edges.iter().flatten() {
        let p = mesh.positions()[*v as usize];
        report.farthest_from_stroke = report
            .farthest_from_stroke
            .max(distance_to_polyline(p, &stroke_on_layer));
    }
    report.path_edges += edges.len();
    let copies = mesh.split_along(&edges);
    report.duplicated += copies.len();
    open(
        mesh,
        (&edges, &copies),
        &near_stroke(points, settings),
        settings,
    );
}

/// Splits, under each projected point farther than `SNAP_SHARE · L` from its face's vertices,
/// the face's edge nearest to it (once per edge); returns each split edge's new vertex by the
/// edge's end vertices.
fn split_under(
    mesh: &mut Mesh,
    projected: &[Option<(u32, Vec3)>],
    edge: f32,
    report: &mut CutReport,
) -> HashMap<(u32, u32), u32> {
    let mut made = HashMap::new();
    for &(face, q) in projected.iter().flatten() {
        let tri = mesh.faces()[face as usize];
        let near = tri
            .iter()
            .map(|&v| mesh.positions()[v as usize].distance(q))
            .fold(f32::INFINITY, f32::min);
        if near <= SNAP_SHARE * edge {
            continue;
        }
        let (a, b, t) = nearest_edge(mesh, tri, q);
        let key = (a.min(b), a.max(b));
        if made.contains_key(&key) || !(0.15..=0.85).contains(&t) {
            continue;
        }
        // Splits keep every earlier edge's end vertices, so the pair still names an edge.
        if let Some(corner) = mesh.find_edge(a, b) {
            let (from, _) = mesh.edge_vertices(corner);
            let along = if from == a { t } else { 1.0 - t };
            made.insert(key, mesh.split_edge(corner, along));
            report.splits += 1;
        }
    }
    made
}

/// Where `a` and `b` are the far corners of two faces sharing an edge (the stroke ran across
/// that edge with no point near enough to it to split it), splits that edge where the segment
/// from `a` to `b` passes it: the path then runs along the stroke instead of round it, through
/// a corner up to 0.87·L off (an equilateral pair's shared edge's end).
fn split_between(mesh: &mut Mesh, a: u32, b: u32, report: &mut CutReport) {
    let shared = mesh.adjacency().corners_around(a).find(|&corner| {
        let twin = mesh.adjacency().opposite[corner as usize];
        twin != crate::mesh::INVALID && mesh.corner_vertex(twin) == b
    });
    let Some(corner) = shared else {
        return;
    };
    let p = |v: u32| mesh.positions()[v as usize];
    let (w, z) = mesh.edge_vertices(corner);
    // The point of w–z nearest to the line through a and b (Ericson, "closest points of two
    // lines"), as a parameter from w.
    let (along, across, between) = (p(b) - p(a), p(z) - p(w), p(a) - p(w));
    let (aa, ab, zz) = (along.dot(along), along.dot(across), across.dot(across));
    let (ac, zc) = (along.dot(between), across.dot(between));
    let denominator = aa * zz - ab * ab;
    if denominator <= f32::EPSILON * aa * zz {
        return;
    }
    let s = (ab * zc - ac * zz) / denominator;
    let t = (ab * s + zc) / zz;
    if (0.15..=0.85).contains(&t) {
        mesh.split_edge(corner, t);
        report.splits += 1;
    }
}

/// The edge of `tri` nearest to `q`: its ends and `q`'s parameter along it from the first.
fn nearest_edge(mesh: &Mesh, tri: [u32; 3], q: Vec3) -> (u32, u32, f32) {
    let p = |v: u32| mesh.positions()[v as usize];
    (0..3)
        .map(|k| {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let (t, on) = closest_on_segment(q, p(a), p(b));
            (a, b, t, on.distance_squared(q))
        })
        .min_by(|x, y| x.3.total_cmp(&y.3))
        .map(|(a, b, t, _)| (a, b, t))
        .expect("a triangle has edges")
}

/// The vertex nearest to `q` among `face`'s (as it was projected on) and those split into
/// its edges.
fn snap(mesh: &Mesh, face: u32, q: Vec3, split: &HashMap<(u32, u32), u32>) -> u32 {
    let tri = mesh.faces()[face as usize];
    let mut candidates: Vec<u32> = tri.to_vec();
    for k in 0..3 {
        let (a, b) = (tri[k], tri[(k + 1) % 3]);
        candidates.extend(split.get(&(a.min(b), a.max(b))));
    }
    // The face may itself have been split: its vertices' split edges count too.
    for (&(a, b), &m) in split {
        if tri.contains(&a) || tri.contains(&b) {
            candidates.push(m);
        }
    }
    let distance = |v: &u32| mesh.positions()[*v as usize].distance_squared(q);
    candidates
        .into_iter()
        .min_by(|x, y| distance(x).total_cmp(&distance(y)).then(x.cmp(y)))
        .expect("a face has vertices")
}

/// A vertex on the mesh's rim within `SNAP_SHARE · L` of `q` (where the stroke left the
/// layer, on or beside `face`), made by splitting the rim edge under `q` where no vertex is
/// that near. The rim edges of the faces around `face`'s corners are searched: the splits
/// under the stroke may have moved the edge to a neighbour.
fn rim_vertex(mesh: &mut Mesh, face: u32, q: Vec3, edge: f32) -> Option<u32> {
    let p = |mesh: &Mesh, v: u32| mesh.positions()[v as usize];
    let mut rim_edges: Vec<u32> = Vec::new();
    for v in mesh.faces()[face as usize] {
        for f in mesh.faces_around(v).collect::<Vec<_>>() {
            for k in 0..3 {
                let corner = 3 * f + k;
                if mesh.adjacency().opposite[corner as usize] == crate::mesh::INVALID {
                    rim_edges.push(corner);
                }
            }
        }
    }
    let (corner, t, _) = rim_edges
        .into_iter()
        .map(|corner| {
            let (a, b) = mesh.edge_vertices(corner);
            let (t, on) = closest_on_segment(q, p(mesh, a), p(mesh, b));
            (corner, t, on.distance_squared(q))
        })
        .min_by(|x, y| x.2.total_cmp(&y.2).then(x.0.cmp(&y.0)))?;
    let (a, b) = mesh.edge_vertices(corner);
    let length = p(mesh, a).distance(p(mesh, b));
    if t * length <= SNAP_SHARE * edge && t <= 0.5 {
        Some(a)
    } else if (1.0 - t) * length <= SNAP_SHARE * edge {
        Some(b)
    } else {
        Some(mesh.split_edge(corner, t))
    }
}

/// The shortest path of edges from `a` to `b` (Dijkstra, by length), or `None` where it would
/// cost more than a detour allows (the two are not near on the surface).
fn shortest_path(mesh: &Mesh, a: u32, b: u32, edge: f32) -> Option<Vec<u32>> {
    let p = |v: u32| mesh.positions()[v as usize];
    let line = [p(a), p(b)];
    let budget = DETOUR * (p(a).distance(p(b)) + 2.0 * edge);
    let mut best: HashMap<u32, (f32, u32)> = HashMap::from([(a, (0.0, a))]);
    let mut queue = BinaryHeap::from([(Reverse(0u32), a)]);
    while let Some((Reverse(bits), v)) = queue.pop() {
        let cost = f32::from_bits(bits);
        if v == b {
            let mut path = vec![b];
            while *path.last().expect("non-empty") != a {
                path.push(best[path.last().expect("non-empty")].1);
            }
            path.reverse();
            return Some(path);
        }
        if cost > best[&v].0 {
            continue;
        }
        for w in mesh.neighbours(v) {
            // Each edge costs its length and how far it strays from the straight line, so
            // that of equally short paths the one nearest the stroke is taken.
            let next = cost + p(v).distance(p(w)) + STRAY_COST * distance_to_polyline(p(w), &line);
            if next <= budget && best.get(&w).is_none_or(|&(c, _)| next < c) {
                best.insert(w, (next, v));
                // Non-negative floats order as their bits do.
                queue.push((Reverse(next.to_bits()), w));
            }
        }
    }
    None
}

fn distance_to_polyline(p: Vec3, line: &[Vec3]) -> f32 {
    if line.len() == 1 {
        return p.distance(line[0]);
    }
    line.windows(2)
        .map(|s| p.distance(closest_on_segment(p, s[0], s[1]).1))
        .fold(f32::INFINITY, f32::min)
}

/// Moves both sides of every duplicated vertex half the collision distance apart, each across
/// the path's smoothed direction toward its own side (less where a face would turn over),
/// then remeshes the band. Across the smoothed direction, not toward each wedge: a path that
/// zigzags between edges moves each side as one, so the two never cross.
fn open(
    mesh: &mut Mesh,
    (path, copies): (&[[u32; 2]], &[[u32; 2]]),
    region: &Aabb,
    settings: &CutSettings,
) {
    if copies.is_empty() {
        return;
    }
    let along = path_directions(mesh, path);
    let mut moved: Vec<u32> = copies.iter().flatten().copied().collect();
    moved.sort_unstable();
    moved.dedup();
    let original: HashMap<u32, u32> = copies.iter().map(|&[o, c]| (c, o)).collect();
    let targets: Vec<(u32, Vec3, Vec3)> = moved
        .iter()
        .filter_map(|&v| {
            let direction = along.get(original.get(&v).unwrap_or(&v))?;
            let across = mesh.normals()[v as usize]
                .cross(*direction)
                .try_normalize()?;
            let p = mesh.positions()[v as usize];
            let side: Vec3 = mesh
                .faces_around(v)
                .map(|f| mesh.face_positions(f as usize).iter().sum::<Vec3>() / 3.0 - p)
                .sum();
            let sign = if side.dot(across) >= 0.0 { 1.0 } else { -1.0 };
            // Where the path's direction cannot open it (its end, on the rim), straight
            // into its own side.
            let into = (side - mesh.normals()[v as usize] * side.dot(mesh.normals()[v as usize]))
                .normalize_or_zero();
            let half = settings.collision_distance / 2.0;
            Some((v, across * sign * half, into * half))
        })
        .collect();
    let on_path: std::collections::HashSet<u32> =
        path.iter().flatten().chain(&moved).copied().collect();
    // Every face is held to its normal from before the opening: moves of its corners one
    // after another must not add up to a fold.
    let start: HashMap<u32, Vec3> = moved
        .iter()
        .flat_map(|&v| mesh.faces_around(v).collect::<Vec<_>>())
        .map(|f| (f, mesh.face_normal(f as usize)))
        .collect();
    for (v, offset, fallback) in targets {
        if !open_vertex(mesh, v, offset, &start) && !open_vertex(mesh, v, fallback, &start) {
            // A wedge too thin to move into (a cut's end on the rim): slide along the rim.
            let p = mesh.positions()[v as usize];
            let rim = mesh
                .neighbours(v)
                .into_iter()
                .find(|w| !on_path.contains(w));
            if let Some(w) = rim.filter(|_| mesh.is_boundary_vertex(v)) {
                let to = mesh.positions()[w as usize] - p;
                let step = to.normalize_or_zero()
                    * (0.45 * to.length()).min(settings.collision_distance / 2.0);
                open_vertex(mesh, v, step, &start);
            }
        }
    }
    let mut touched = moved.clone();
    for &v in &moved {
        touched.extend(mesh.neighbours(v));
    }
    touched.sort_unstable();
    touched.dedup();
    mesh.recompute_normals_at(&touched);
    let mut remesh = RemeshSettings::new(settings.edge);
    remesh.collision_distance = settings.collision_distance;
    // The remesher reads the grid only around the band: a grid of what is near the stroke
    // serves it as the whole mesh's would, without an O(mesh) build.
    if let Ok(mut grid) = SpatialHash::new(settings.edge, mesh.vertex_count()) {
        for v in 0..mesh.vertex_count() as u32 {
            let p = mesh.positions()[v as usize];
            if mesh.is_vertex_live(v) && region.distance_squared_to(p) == 0.0 {
                grid.insert(v, p);
            }
        }
        remesh_region(mesh, &mut grid, &touched, &remesh);
    }
}

/// A box holding everything a cut along `points` can change, and what the remesher and the
/// exact test look at around it: the reach of the projection, the band the remesher works on
/// and its queries' reach.
fn near_stroke(points: &[Vec3], settings: &CutSettings) -> Aabb {
    Aabb::of_points(points).expanded(settings.reach + 8.0 * settings.edge)
}

/// The direction of the path at each of its vertices, smoothed over two edges either side
/// (a path through split and original vertices zigzags about the stroke).
fn path_directions(mesh: &Mesh, path: &[[u32; 2]]) -> HashMap<u32, Vec3> {
    let mut order: Vec<u32> = Vec::with_capacity(path.len() + 1);
    for &[a, b] in path {
        if order.last() != Some(&a) {
            order.push(a);
        }
        order.push(b);
    }
    let p = |i: usize| mesh.positions()[order[i] as usize];
    let last = order.len().saturating_sub(1);
    let mut directions = HashMap::new();
    for (i, &v) in order.iter().enumerate() {
        let (from, to) = (i.saturating_sub(2), (i + 2).min(last));
        if let Some(d) = (p(to) - p(from)).try_normalize() {
            directions.entry(v).or_insert(d);
        }
    }
    directions
}

/// Moves `v` by `offset`; halves the move while a face around it would turn more than 60°
/// from its normal at the `start` of the opening. Whether it moved at all.
fn open_vertex(mesh: &mut Mesh, v: u32, offset: Vec3, start: &HashMap<u32, Vec3>) -> bool {
    let p = mesh.positions()[v as usize];
    let faces: Vec<u32> = mesh.faces_around(v).collect();
    let before: Vec<Vec3> = faces.iter().map(|f| start[f]).collect();
    let mut step = offset;
    for _ in 0..OPENING_TRIES {
        mesh.positions_mut()[v as usize] = p + step;
        let kept = faces
            .iter()
            .zip(&before)
            .all(|(&f, n)| mesh.face_normal(f as usize).dot(*n) > 0.5);
        if kept {
            return true;
        }
        step /= 2.0;
    }
    mesh.positions_mut()[v as usize] = p;
    false
}
