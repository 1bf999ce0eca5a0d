//! Culling within a layer: the parts of a step's region where a layer is a *sheet*, a surface
//! that cannot come within the collision distance of itself, so the searches of a vertex
//! against its own layer there (the proximity clamp's, the backstop's) are skipped. A plain
//! draw on one flat layer then tests nothing against nothing, where it used to prove, face by
//! face, that the sheet does not touch itself.
//!
//! The test is the normal-cone test of Volino & Magnenat-Thalmann (a surface whose normals lie
//! in a cone of half-angle < 90° around an axis `a`, and whose boundary projected along `a` is
//! one simple loop, projects one-to-one onto the plane across `a`), adapted to proximity. It
//! has two levels: a layer that projects one-to-one is a sheet, and no two of its faces meet
//! beyond what they share, so the backstop's pair tests within it are skipped; a sheet that
//! also passes the bound below is *clear*: no vertex of it comes within `d` of its own faces
//! outside the exclusion ring, so the proximity clamp's searches within it are skipped too.
//! A ridge drawn over and over is a sheet whose flanks are too steep to be clear; there a
//! moving vertex may still be clear by its own neighbourhood ([`clear_around`]), a bound on
//! the vertex's distance to its sheet taken from the projection of its exclusion ring alone.
//!
//! **Why no vertex of a clear sheet comes within `d` of a face of it outside its exclusion
//! ring.** Let `S` be the region's faces of one layer, every unit normal `n` with
//! `n·a ≥ cos θ > 0`, its boundary (edges with one face in `S`) one loop, not on the mesh's
//! rim, simple once projected along `a`, and every boundary edge farther than `d / cos θ`
//! from the box of the step's moves. Then:
//! 1. The projection is one-to-one: all faces keep their orientation in it, so a point of the
//!    plane has as many points of `S` above it as the projected loop winds around it, 0 or 1.
//!    (This alone makes a sheet.)
//! 2. A straight segment of length `h` in the projection of `S` lifts to a path on `S` no
//!    longer than `h / cos θ` (a face's slope along any direction is at most `tan θ`).
//! 3. A moving vertex `v` (inside the box of the moves) is more than `d` from the boundary in
//!    the projection: the segment to the nearest boundary point lifts to a path shorter than
//!    `d / cos θ`, which would end nearer `v` than every boundary edge is.
//! 4. Let `φ` be the graph distance from `v`, interpolated linearly over each face. Neighbours
//!    differ by at most 1, so on a face `|∇φ| ≤ 1 / ρ`, `ρ` the face's smallest altitude. A
//!    face outside `v`'s `r`-ring has `φ ≥ r + 1`, so any path to it on `S` is at least
//!    `(r + 1)·ρ_min` long.
//! 5. A point `q` of such a face with `|v − q| < d` would be above the disk of radius `d`
//!    around `v` (inside `S`'s projection by 3), reached by a lifted segment of length at most
//!    `|v − q| / cos θ` (by 2), so `|v − q| ≥ cos θ·(r + 1)·ρ_min`. The clear test asks for
//!    that to be at least `d`, with a margin for rounding.
//!
//! By 1 no two faces of a sheet meet beyond what they share either, so the backstop's pair
//! tests within it find nothing. The test costs one pass over the region's faces and its
//! boundary; `tests/culling.rs` compares culled and unculled strokes on folded, pinched,
//! twisted, crumpled and ridged sheets, which must end identical.

use glam::{DVec2, DVec3, Vec3};

use super::neighbourhood::in_ring;
use super::region::Region;
use super::state::StrokeState;
use crate::geom::Aabb;
use crate::mesh::{INVALID, Mesh, face_of, next, prev};

/// Relative margin on the distance bound: far above `f32` rounding in the clamp's distances.
const MARGIN: f64 = 1e-3;

/// Per layer id: the region's faces of that layer as a sheet where the mesh is now, if they
/// are one (the module's conditions), for the `layers` present in the region. Where the region
/// is one layer and a sheet not clear as a whole, `slopes` gets its faces' [`FaceSlope`]s, in
/// the region's order, for [`clear_around`]; it is left empty otherwise. (Callers that only
/// ask whether the sheet is clear, the GPU's, pay for them too: a root and a division a face.)
pub(super) fn find_sheets(
    state: &StrokeState<'_>,
    mesh: &Mesh,
    region: &Region,
    layers: &[u32],
    slopes: &mut Vec<FaceSlope>,
) -> Vec<Option<Sheet>> {
    slopes.clear();
    let mut sheets = vec![None; mesh.layer_count()];
    for &layer in layers {
        let faces = faces_of_layer(mesh, region, layer);
        let slopes = region.single_layer().then_some(&mut *slopes);
        sheets[layer as usize] = sheet_of(state, mesh, region, &faces, slopes);
    }
    sheets
}

/// Faces of one layer in a step's region that project one-to-one along their normal cone's
/// axis: no two meet beyond what they share.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sheet {
    /// No vertex of the sheet comes within the collision distance of a face of it outside
    /// its exclusion ring (the module's bound).
    pub(crate) clear: bool,
    /// Two unit vectors across the axis the sheet projects one-to-one along.
    frame: [DVec3; 2],
}

/// The region's faces of `layer`, in the region's order.
pub(super) fn faces_of_layer<'r>(
    mesh: &Mesh,
    region: &'r Region,
    layer: u32,
) -> std::borrow::Cow<'r, [u32]> {
    if region.single_layer() {
        return std::borrow::Cow::Borrowed(&region.faces);
    }
    let layers = mesh.face_layers();
    let faces = region.faces.iter().copied();
    std::borrow::Cow::Owned(faces.filter(|&f| layers[f as usize] == layer).collect())
}

fn sheet_of(
    state: &StrokeState<'_>,
    mesh: &Mesh,
    region: &Region,
    faces: &[u32],
    slopes: Option<&mut Vec<FaceSlope>>,
) -> Option<Sheet> {
    let layers = mesh.face_layers();
    let layer = layers[faces[0] as usize];
    let in_set = |g: u32| layers[g as usize] == layer && region.local(g).is_some();
    let loop_of = || boundary_loop(mesh, faces, in_set);
    let shapes_of = || face_shapes(mesh, faces, |v: u32| mesh.positions()[v as usize]);
    // Two walks over the faces, about even: one on each core. On one thread, the loop first:
    // a layer with a rim in the region (a flake, a peeling patch) is no sheet, found without
    // computing a normal.
    let (boundary, shapes) = if state.parallel {
        let (boundary, shapes) = rayon::join(loop_of, shapes_of);
        (boundary?, shapes)
    } else {
        (loop_of()?, shapes_of())
    };
    let cone = cone_of(&shapes)?;
    if !projected_loop_is_simple(mesh, &boundary, cone.axis) {
        return None;
    }
    let d = state.collision_distance as f64 * (1.0 + MARGIN);
    let far_enough = d / cone.cos;
    let edge_far = |(u, w): (u32, u32)| {
        let (p, q) = (mesh.positions()[u as usize], mesh.positions()[w as usize]);
        box_gap(&region.bounds, &Aabb::of_points(&[p, q])) > far_enough
    };
    let ends = boundary.windows(2).map(|w| (w[0], w[1]));
    let closing = (boundary[boundary.len() - 1], boundary[0]);
    let clear = cone.cos * (state.ring + 1) as f64 * cone.min_altitude >= d
        && ends.chain(std::iter::once(closing)).all(edge_far);
    if let Some(slopes) = slopes.filter(|_| !clear) {
        let slope = |&(n, longest): &(DVec3, f64)| FaceSlope::of(n, longest, cone.axis);
        slopes.extend(shapes.iter().map(slope));
    }
    let (u, w) = cone.axis.any_orthonormal_pair();
    Some(Sheet {
        clear,
        frame: [u, w],
    })
}

/// How steep a face of a sheet stands to the sheet's axis, and how thin it is: what the
/// per-vertex bound of [`clear_around`] reads.
#[derive(Debug, Clone, Copy)]
pub(super) struct FaceSlope {
    /// `n·axis` for the face's unit normal `n`.
    cos: f64,
    /// The face's smallest altitude.
    altitude: f64,
}

impl FaceSlope {
    /// Of a face whose normal is `n` (twice its area long) and longest edge squared `longest`.
    fn of(n: DVec3, longest: f64, axis: DVec3) -> FaceSlope {
        let area_twice = n.length();
        FaceSlope {
            cos: n.dot(axis) / area_twice,
            altitude: area_twice / longest.sqrt(),
        }
    }
}

/// Whether no face of `sheet` outside the exclusion ring `ring` (sorted, `v` included) of `v`,
/// `depth` its graph radius, comes within `d` of `v` where the mesh is now, by `v`'s own
/// neighbourhood: the module's per-vertex bound, which holds on a sheet that is not clear as a
/// whole (a ridge's flat foot beside its steep flanks). The sheet must be the region's faces
/// of `v`'s layer, the region one layer.
///
/// **Why.** Let `star` be the faces with a vertex in the ring (those the clamp skips as `v`'s
/// neighbourhood), all in the sheet, and `P` the projection along the sheet's axis. `v` is not
/// on the rim and its faces keep their orientation in `P`, so `P(v)` lies inside `P(star)`. A
/// point `q` of a sheet face outside `star` projects outside the inside of `P(star)` (the
/// projection is one-to-one), so the segment from `P(v)` to `P(q)` crosses the boundary of
/// `P(star)` and `|v − q| ≥ |P(v) − P(q)|` is at least `P(v)`'s distance to it. That boundary
/// is the projection of `star`'s edges with no `star` face across them: both their ends lie
/// outside the ring (a face across an edge shares its ends), so each has one face with a ring
/// vertex. Every face within `d` of a moving vertex is in the region, so a distance of `d` or
/// more settles it; two bounds on it are tried, the cheap one first
/// ([`clear_by_slopes`], [`clear_by_projection`]).
pub(super) fn clear_around(
    mesh: &Mesh,
    region: &Region,
    sheet: &Sheet,
    (v, ring, depth): (u32, &[u32], u32),
    d: f32,
) -> bool {
    let here = mesh.positions()[v as usize];
    // f32 rounding in the clamp's distances, relative to d and to the coordinates.
    let rounding = 16.0 * f32::EPSILON as f64 * here.abs().max_element() as f64;
    let needed = d as f64 * (1.0 + MARGIN) + rounding;
    // The ring holds `v`: its rim check is `v`'s too.
    for &a in ring {
        // A ring vertex where the region reaches was gathered with all its faces: it had not
        // moved since, or it moves, and lies in the box of the moves.
        let gathered = region.covers(&Aabb::of_points(&[mesh.positions()[a as usize]]));
        if mesh.is_boundary_vertex(a) || !gathered {
            return false;
        }
    }
    clear_by_slopes(mesh, region, ring, depth) >= needed
        || clear_by_projection(mesh, sheet, (v, ring), needed)
}

/// A lower bound on `P(v)`'s distance to the boundary of `P(star)` ([`clear_around`]) from the
/// star's faces alone: `cos θ·(r + 1)·ρ`, `θ` the widest angle of a star face's normal to the
/// axis, `ρ` the star's smallest altitude, `r` the ring's depth. A handful of reads per ring
/// vertex, where the projection walks the star's rim: on the 1M plane's draws it clears 85 %
/// of the vertices the projection clears.
///
/// **Why.** Take the segment from `P(v)` to the nearest point `y` of the boundary: it lies in
/// `P(star)`, so it lifts to a path on `star` from `v` to a rim edge of `star`. Let `φ` be the
/// graph distance from `v`, interpolated linearly over each face: 0 at `v`, `r + 1` on the rim
/// edges (their ends are outside the ring and next to a ring vertex). Neighbours differ by at
/// most 1, so on a face `|∇φ| ≤ 1 / ρ`, and the path is at least `(r + 1)·ρ` long. Projecting
/// a face shortens no length below `cos θ` times itself, so `|P(v) − y| ≥ cos θ·(r + 1)·ρ`.
fn clear_by_slopes(mesh: &Mesh, region: &Region, ring: &[u32], depth: u32) -> f64 {
    let (mut cos, mut altitude) = (f64::INFINITY, f64::INFINITY);
    for &a in ring {
        for c in mesh.adjacency().corners_around(a) {
            let local = region.local(face_of(c));
            let Some(slope) = local.and_then(|l| region.slopes.get(l)) else {
                return 0.0;
            };
            cos = cos.min(slope.cos);
            altitude = altitude.min(slope.altitude);
        }
    }
    cos * (depth + 1) as f64 * altitude
}

/// Whether `P(v)` lies `needed` or farther from the boundary of `P(star)` ([`clear_around`]),
/// measured: the projected distance to each of the star's rim edges, each met once, from the
/// ring vertex of the one face that holds it.
fn clear_by_projection(mesh: &Mesh, sheet: &Sheet, (v, ring): (u32, &[u32]), needed: f64) -> bool {
    let [u, w] = sheet.frame;
    let flat = |a: u32| {
        let p = mesh.positions()[a as usize].as_dvec3();
        DVec2::new(p.dot(u), p.dot(w))
    };
    let needed_squared = needed * needed;
    let x = flat(v);
    let outside = |a: u32| !in_ring(ring, a);
    let table = mesh.adjacency();
    for &a in ring {
        for c in table.corners_around(a) {
            // Around a, corner c's face holds the edge (next, prev) opposite a.
            let (b0, b1) = (mesh.corner_vertex(next(c)), mesh.corner_vertex(prev(c)));
            if !(outside(b0) && outside(b1)) {
                continue;
            }
            let o = table.opposite[c as usize];
            if o != INVALID && !outside(mesh.corner_vertex(o)) {
                continue;
            }
            if squared_distance_to_segment(x, (flat(b0), flat(b1))) < needed_squared {
                return false;
            }
        }
    }
    true
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct Cone {
    pub(crate) axis: DVec3,
    /// The smallest `n·axis` over the faces' unit normals.
    pub(crate) cos: f64,
    pub(crate) min_altitude: f64,
}

/// The faces' normals' cone around their area-weighted mean, and their smallest altitude, with
/// vertices where `position` puts them; none for a degenerate face or a cone as wide as a
/// hemisphere. On one thread: a step's region holds a few thousand faces, and over rayon the
/// cone took 0.34 ms a step against 0.20 on one (draws on the 1M plane, two cores).
pub(crate) fn normal_cone(
    mesh: &Mesh,
    faces: &[u32],
    position: impl Fn(u32) -> Vec3,
) -> Option<Cone> {
    cone_of(&face_shapes(mesh, faces, position))
}

/// Per face: its normal (twice its area long) and its longest edge, squared.
fn face_shapes(mesh: &Mesh, faces: &[u32], position: impl Fn(u32) -> Vec3) -> Vec<(DVec3, f64)> {
    let shape = |&f: &u32| {
        let [a, b, c] = mesh.faces()[f as usize].map(|v| position(v).as_dvec3());
        let (ab, bc, ca) = (b - a, c - b, a - c);
        let longest = ab
            .length_squared()
            .max(bc.length_squared())
            .max(ca.length_squared());
        (ab.cross(-ca), longest)
    };
    faces.iter().map(shape).collect()
}

/// [`normal_cone`] of faces' [`face_shapes`].
fn cone_of(shapes: &[(DVec3, f64)]) -> Option<Cone> {
    // Summed in the region's order, which is the same on every run.
    let axis = shapes.iter().map(|s| s.0).sum::<DVec3>().try_normalize()?;
    // The smallest cos², and altitude², without a root per face.
    let mut cos_squared = 1.0f64;
    let mut altitude_squared = f64::INFINITY;
    for &(n, longest) in shapes {
        let (along, area_squared) = (n.dot(axis), n.length_squared());
        if along <= 0.0 || area_squared == 0.0 {
            return None;
        }
        cos_squared = cos_squared.min(along * along / area_squared);
        altitude_squared = altitude_squared.min(area_squared / longest);
    }
    Some(Cone {
        axis,
        cos: cos_squared.sqrt(),
        min_altitude: altitude_squared.sqrt(),
    })
}

/// The vertices of the one loop that bounds `faces` (those `in_set` says belong), in order;
/// none when the faces touch the mesh's rim, or their boundary is several loops or passes a
/// vertex twice.
pub(crate) fn boundary_loop(
    mesh: &Mesh,
    faces: &[u32],
    in_set: impl Fn(u32) -> bool,
) -> Option<Vec<u32>> {
    let opposite = &mesh.adjacency().opposite;
    // Each edge directed as its face runs: next(c) → prev(c) for the corner facing it.
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for &f in faces {
        for c in 3 * f..3 * f + 3 {
            let o = opposite[c as usize];
            if o == INVALID {
                return None;
            }
            if !in_set(face_of(o)) {
                edges.push((mesh.corner_vertex(next(c)), mesh.corner_vertex(prev(c))));
            }
        }
    }
    one_loop(edges)
}

/// The vertices of the mesh's rim, in order, when `faces` (every live face) are bounded by one
/// loop of rim edges that passes no vertex twice; none otherwise (a closed mesh, several loops).
pub(crate) fn rim_loop(mesh: &Mesh, faces: &[u32]) -> Option<Vec<u32>> {
    let opposite = &mesh.adjacency().opposite;
    let edges = faces
        .iter()
        .flat_map(|&f| 3 * f..3 * f + 3)
        .filter(|&c| opposite[c as usize] == INVALID)
        .map(|c| (mesh.corner_vertex(next(c)), mesh.corner_vertex(prev(c))))
        .collect();
    one_loop(edges)
}

/// The directed `edges` chained into one loop of vertices, in order; none when they make
/// several loops, pass a vertex twice, or are fewer than three.
fn one_loop(mut edges: Vec<(u32, u32)>) -> Option<Vec<u32>> {
    if edges.len() < 3 {
        return None;
    }
    edges.sort_unstable();
    if edges.windows(2).any(|w| w[0].0 == w[1].0) {
        return None;
    }
    let mut ordered = Vec::with_capacity(edges.len());
    let mut at = edges[0].0;
    for _ in 0..edges.len() {
        ordered.push(at);
        let i = edges.binary_search_by_key(&at, |e| e.0).ok()?;
        at = edges[i].1;
        if at == ordered[0] {
            break;
        }
    }
    (at == ordered[0] && ordered.len() == edges.len()).then_some(ordered)
}

/// The per-axis gap between two boxes (0 when they overlap): a lower bound on the distance
/// between any point of one and any point of the other.
fn box_gap(a: &Aabb, b: &Aabb) -> f64 {
    let gap = (a.min - b.max).max(b.min - a.max).max(Vec3::ZERO);
    gap.max_element() as f64
}

/// Whether the closed polyline through `loop_vertices`, projected along `axis`, is simple:
/// no two edges closer than a hair (touching counts as crossing), no edge folded back onto
/// the next. Edges are bucketed in a grid of cells about one edge long.
pub(crate) fn projected_loop_is_simple(mesh: &Mesh, loop_vertices: &[u32], axis: DVec3) -> bool {
    let (u, w) = axis.any_orthonormal_pair();
    let points: Vec<DVec2> = loop_vertices
        .iter()
        .map(|&v| {
            let p = mesh.positions()[v as usize].as_dvec3();
            DVec2::new(p.dot(u), p.dot(w))
        })
        .collect();
    let n = points.len();
    let edge = |i: usize| (points[i], points[(i + 1) % n]);
    let longest = (0..n)
        .map(|i| edge(i).0.distance(edge(i).1))
        .fold(0.0f64, f64::max);
    if longest == 0.0 {
        return false;
    }
    let hair = 1e-6 * longest;
    // Consecutive edges may only meet at their shared point.
    for i in 0..n {
        let (a, b) = edge(i);
        let c = edge((i + 1) % n).1;
        let (back, ahead) = (a - b, c - b);
        if back.perp_dot(ahead).abs() <= hair * back.length() && back.dot(ahead) > 0.0 {
            return false;
        }
    }
    let lo = points.iter().copied().fold(DVec2::INFINITY, DVec2::min);
    let cell_of = |p: DVec2| ((p - lo) / longest).floor().as_ivec2();
    let mut cells: Vec<(glam::IVec2, u32)> = Vec::with_capacity(4 * n);
    for i in 0..n {
        let (a, b) = edge(i);
        let (c0, c1) = (cell_of(a.min(b) - hair), cell_of(a.max(b) + hair));
        for x in c0.x..=c1.x {
            for y in c0.y..=c1.y {
                cells.push((glam::IVec2::new(x, y), i as u32));
            }
        }
    }
    cells.sort_unstable_by_key(|&(c, i)| (c.x, c.y, i));
    let apart = |i: usize, j: usize| {
        let adjacent = (i + 1) % n == j || (j + 1) % n == i;
        adjacent || segments_apart(edge(i), edge(j), hair)
    };
    cells.chunk_by(|a, b| a.0 == b.0).all(|cell| {
        cell.iter().enumerate().all(|(k, &(_, i))| {
            cell[k + 1..]
                .iter()
                .all(|&(_, j)| apart(i as usize, j as usize))
        })
    })
}

/// Whether two segments neither cross nor come within `hair` of each other.
fn segments_apart((a, b): (DVec2, DVec2), (c, d): (DVec2, DVec2), hair: f64) -> bool {
    let side = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let crossing = side(a, b, c) * side(a, b, d) < 0.0 && side(c, d, a) * side(c, d, b) < 0.0;
    if crossing {
        return false;
    }
    squared_distance_to_segment(a, (c, d))
        .min(squared_distance_to_segment(b, (c, d)))
        .min(squared_distance_to_segment(c, (a, b)))
        .min(squared_distance_to_segment(d, (a, b)))
        > hair * hair
}

fn squared_distance_to_segment(p: DVec2, (s, t): (DVec2, DVec2)) -> f64 {
    let st = t - s;
    let k = ((p - s).dot(st) / st.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    p.distance_squared(s + st * k)
}

#[cfg(test)]
mod tests {
    use glam::Vec2;

    use super::*;
    use crate::collide::neighbourhood::ring_vertices;
    use crate::geom::closest_point_on_triangle;
    use crate::grid::SpatialHash;
    use crate::scene::shapes::stacked_sheets;

    /// Side of the test sheet in cells of edge 1, and of the block of vertices tested.
    const CELLS: u32 = 40;
    const BLOCK: std::ops::Range<u32> = 16..25;

    /// A flat sheet of `CELLS`² unit cells raised to `height` at each vertex.
    fn sheet(height: impl Fn(Vec2) -> f32) -> Mesh {
        let mut mesh = stacked_sheets(1, CELLS, CELLS, 1.0, 0.0);
        for p in mesh.positions_mut() {
            p.z = height(Vec2::new(p.x, p.y));
        }
        mesh.recompute_normals();
        mesh
    }

    /// The nearest face of `v`'s layer outside its exclusion ring, by a walk over every face.
    fn nearest_outside_ring(mesh: &Mesh, v: u32, ring: &[u32]) -> f32 {
        let x = mesh.positions()[v as usize];
        (0..mesh.face_count())
            .filter(|&f| !mesh.faces()[f].iter().any(|&a| in_ring(ring, a)))
            .map(|f| {
                let [a, b, c] = mesh.face_positions(f);
                closest_point_on_triangle(x, a, b, c).distance(x)
            })
            .fold(f32::INFINITY, f32::min)
    }

    /// What the bounds say of one vertex, and the nearest face outside its ring.
    struct Verdict {
        /// `clear_around`'s answer, and each of its two bounds' alone.
        clear: bool,
        by_slopes: bool,
        by_projection: bool,
        nearest: f32,
    }

    /// Per vertex of the middle block: what the bounds say; none when the block's region is
    /// not a sheet.
    fn verdicts(mesh: &Mesh, d: f32, ring: u32) -> Option<Vec<Verdict>> {
        let grid = SpatialHash::build(mesh, 1.0).unwrap();
        let active = [true];
        let state = StrokeState {
            collision_distance: d,
            ring,
            ..StrokeState::for_tests(&grid, &active, mesh.longest_edge() * 1.01)
        };
        let row = CELLS + 1;
        let block: Vec<u32> = BLOCK
            .flat_map(|y| BLOCK.map(move |x| y * row + x))
            .collect();
        let selection: Vec<(u32, f32)> = block.iter().map(|&v| (v, 1.0)).collect();
        let targets: Vec<Vec3> = block
            .iter()
            .map(|&v| mesh.positions()[v as usize])
            .collect();
        let mut target_of = vec![INVALID; mesh.vertex_count()];
        for (slot, &v) in block.iter().enumerate() {
            target_of[v as usize] = slot as u32;
        }
        let mut region = Region::default();
        region.size_for(mesh);
        region.gather(&state, mesh, &selection, &targets, &target_of);
        region.find_sheets(&state, mesh);
        let sheet = *region.sheet(0)?;
        let mut ring_of = Vec::new();
        let needed = d as f64 * (1.0 + MARGIN);
        let verdict = |&v: &u32| {
            ring_vertices(mesh, v, ring, &mut ring_of);
            let inside = !ring_of.iter().any(|&a| mesh.is_boundary_vertex(a));
            Verdict {
                clear: clear_around(mesh, &region, &sheet, (v, &ring_of, ring), d),
                by_slopes: inside && clear_by_slopes(mesh, &region, &ring_of, ring) >= needed,
                by_projection: inside && clear_by_projection(mesh, &sheet, (v, &ring_of), needed),
                nearest: nearest_outside_ring(mesh, v, &ring_of),
            }
        };
        Some(block.iter().map(verdict).collect())
    }

    /// Neither bound ever clears a vertex that has a face of its sheet within `d` outside its
    /// ring, on bumps and a groove steep enough that the sheet as a whole is not clear, and
    /// at distances where the ring's own next faces come within reach; and together they
    /// clear most vertices where nothing is near, and each bound alone clears some
    /// (here the slopes 201 of the projection's 972).
    #[test]
    fn a_vertex_is_cleared_only_where_nothing_outside_its_ring_is_within_reach() {
        let bumps = |amplitude: f32, width: f32| {
            move |p: Vec2| {
                let centres = [(18.0, 19.0, 1.0), (23.0, 21.5, -0.7), (20.5, 24.0, 0.5)];
                let bump = |&(x, y, sign): &(f32, f32, f32)| {
                    let r2 = p.distance_squared(Vec2::new(x, y));
                    sign * amplitude * (-r2 / (width * width)).exp()
                };
                centres.iter().map(bump).sum::<f32>()
            }
        };
        let groove = |p: Vec2| -6.0 * (1.0 - (p.x - 20.3).abs() / 1.6).max(0.0);
        let mut meshes: Vec<Mesh> = vec![sheet(|_| 0.0), sheet(groove)];
        for (amplitude, width) in [(1.0, 3.0), (2.5, 2.5), (3.5, 2.0), (5.0, 3.0)] {
            meshes.push(sheet(bumps(amplitude, width)));
        }
        let (mut cleared, mut kept_near, mut kept_far) = (0, 0, 0);
        let (mut by_slopes, mut by_projection) = (0, 0);
        for (m, mesh) in meshes.iter().enumerate() {
            for (d, ring) in [(0.8, 1), (1.0, 1), (1.5, 1), (2.5, 1), (2.5, 2)] {
                let Some(verdicts) = verdicts(mesh, d, ring) else {
                    continue;
                };
                for Verdict {
                    clear,
                    by_slopes: slopes,
                    by_projection: projection,
                    nearest,
                } in verdicts
                {
                    let near = nearest < d;
                    assert!(
                        !(clear || slopes || projection) || !near,
                        "mesh {m}, d {d}: {nearest} cleared ({clear}, {slopes}, {projection})"
                    );
                    by_slopes += usize::from(slopes);
                    by_projection += usize::from(projection);
                    match (clear, near) {
                        (true, _) => cleared += 1,
                        (false, true) => kept_near += 1,
                        (false, false) => kept_far += 1,
                    }
                }
            }
        }
        assert!(
            cleared > 500 && kept_near > 500 && kept_far > 0,
            "{cleared} cleared, {kept_near} kept with a face near, {kept_far} kept needlessly"
        );
        assert!(
            by_slopes > 0 && by_projection > 0,
            "{by_slopes} cleared by the slopes, {by_projection} by the projection"
        );
    }
}
