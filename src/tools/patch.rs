//! A new layer from a closed stroke (sLayer, "Editing Tools": "draw a closed stroke onto a
//! surface and create a new layer from it using discrete coons patches"): the outline is
//! projected onto the layer it is drawn on and resampled at `L`, split into four sides at its
//! sharpest corners (or evenly, where it has none), filled with a discrete Coons patch laid out
//! as a triangular lattice (`Layout`), the patch's points projected onto the surface, and the
//! whole lifted off it like a duplicate: along the normals, clear of everything, remeshed to
//! `L`, checked exactly.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::ToolError;
use super::duplicate::{DuplicateReport, DuplicateSettings, check_settings, lift_off};
use super::obstacles::Obstacles;
use super::select::check_layer;
use crate::geom::Aabb;
use crate::mesh::{LayerId, Mesh};

/// A corner turns the outline by at least this much (radians, over a window of the outline).
const CORNER_TURN: f32 = 0.6;
/// The outline is closed when its ends are this close (× its perimeter, at least 2 L).
const CLOSING_SHARE: f32 = 0.1;

/// The patch [`patch`] would add for the closed `outline` drawn on `layer`, as a one-layer
/// mesh checked against `mesh`.
pub fn plan_patch(
    mesh: &Mesh,
    outline: &[Vec3],
    layer: LayerId,
    settings: &DuplicateSettings,
) -> Result<(Mesh, DuplicateReport), ToolError> {
    check_settings(mesh, settings)?;
    check_layer(mesh, layer)?;
    let edge = settings.edge;
    if outline.len() < 4 || outline.iter().any(|p| !p.is_finite()) {
        return Err(bad("it needs at least four finite points"));
    }
    let on_layer = OnLayer::near(mesh, outline, layer, edge);
    let projected: Vec<Vec3> = outline
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let point = on_layer.point(p);
            point.ok_or_else(|| bad(&format!("point {i} is not over layer {layer}")))
        })
        .collect::<Result<_, _>>()?;
    let facing = |p: Vec3| on_layer.normal(mesh, p);
    let stretch = rim_stretch(&closed_ring(&projected, edge)?, facing, settings.offset);
    let lay_out = |layout: Layout| {
        let spacing = match layout {
            Layout::Lattice => edge / stretch,
            Layout::Quads => edge,
        };
        let ring = closed_ring(&projected, spacing)?;
        let corners = corners(&flatten(&ring)?);
        let grid = coons_grid(&ring, &corners, spacing, layout);
        // Each point on its own: a big patch's projection would otherwise leave cores idle.
        let positions = grid
            .points
            .par_iter()
            .map(|&p| {
                on_layer
                    .point(p)
                    .ok_or_else(|| bad("it encloses a hole in the layer"))
            })
            .collect::<Result<Vec<Vec3>, _>>()?;
        let piece = triangulate(positions, &grid, settings, facing)?;
        lift_off(mesh, piece, layer, settings)
    };
    let lattice = lay_out(Layout::Lattice);
    if lattice
        .as_ref()
        .is_ok_and(|(piece, _)| piece.live_face_count() >= LATTICE_ONLY_FACES)
    {
        return lattice;
    }
    the_more_even(lattice, lay_out(Layout::Quads))
}

/// The faces of the layer a patch is drawn on, near its outline, for points to be put on.
struct OnLayer {
    surface: Obstacles,
    layer: LayerId,
    /// How far to look, shortest first: most points lie on or near the surface, and the long
    /// look is paid only where the short ones find nothing. A face found within a look is the
    /// nearest of all (any nearer one lies within that look too), so the answer is the one
    /// the long look alone would give.
    looks: [f32; 3],
}

impl OnLayer {
    fn near(mesh: &Mesh, outline: &[Vec3], layer: LayerId, edge: f32) -> OnLayer {
        let bounds = Aabb::of_points(outline);
        let reach = (4.0 * edge).max(0.5 * (bounds.max - bounds.min).length());
        OnLayer {
            surface: Obstacles::near(mesh, bounds.expanded(reach + edge), 1.5 * edge),
            layer,
            looks: [0.5 * edge, 4.0 * edge, reach],
        }
    }

    fn nearest(&self, p: Vec3) -> Option<(u32, Vec3)> {
        let layer = self.layer;
        self.looks
            .iter()
            .find_map(|&look| self.surface.nearest_face(p, look, layer))
    }

    /// The layer's point nearest to `p`.
    fn point(&self, p: Vec3) -> Option<Vec3> {
        self.nearest(p).map(|(_, q)| q)
    }

    /// The normal of the layer's face nearest to `p` (zero where none is in reach).
    fn normal(&self, mesh: &Mesh, p: Vec3) -> Vec3 {
        self.nearest(p)
            .map_or(Vec3::ZERO, |(f, _)| mesh.face_normal(f as usize))
    }
}

/// How much longer `ring` comes out lifted by `offset` along the surface's normals (`facing`).
/// Lifting off a curved surface stretches (or shrinks) a patch: laid out at `L`, a patch lifted
/// 2·L off a sphere 13·L round comes out 15 % long, just below the remesher's split length,
/// and remeshing splits a scatter of its edges in two. Laid out shorter by the stretch its rim
/// takes, it is lifted to `L`.
fn rim_stretch(ring: &[Vec3], facing: impl Fn(Vec3) -> Vec3, offset: f32) -> f32 {
    let lifted: Vec<Vec3> = ring.iter().map(|&p| p + facing(p) * offset).collect();
    (perimeter(&lifted) / perimeter(ring)).clamp(0.5, 2.0)
}

type Planned = Result<(Mesh, DuplicateReport), ToolError>;

/// Of two layouts' patches, the one with the more even edges; the one that could be placed
/// where the other could not; the lattice's error where neither could.
fn the_more_even(lattice: Planned, quads: Planned) -> Planned {
    let evenness =
        |(piece, _): &(Mesh, DuplicateReport)| piece.edge_length_stats().coefficient_of_variation();
    match (lattice, quads) {
        (Ok(a), Ok(b)) => Ok(if evenness(&b) < evenness(&a) { b } else { a }),
        (Ok(a), Err(_)) | (Err(_), Ok(a)) => Ok(a),
        (Err(e), Err(_)) => Err(e),
    }
}

/// How a patch's points are laid out between its four sides.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Layout {
    /// The rows of a triangular lattice, counted on the patch's middle as well as its sides:
    /// the more even past a few hundred faces (edge cv 0.05 against 0.17 on the story's
    /// 40K-face patches, and next to nothing left for remeshing to do).
    Lattice,
    /// A grid of quads counted on the sides, each split along its shorter diagonal: on a
    /// patch a few edges across, bumpy or round, it can come out the more even of the two.
    Quads,
}

/// From this many faces a patch is laid out as a lattice only; a smaller one is laid out both
/// ways (a few milliseconds) and the more even kept.
const LATTICE_ONLY_FACES: usize = 1_000;

/// Adds the patch of the closed `outline` drawn on `layer` as a new layer after the last; on
/// an error the mesh is unchanged.
pub fn patch(
    mesh: &mut Mesh,
    outline: &[Vec3],
    layer: LayerId,
    settings: &DuplicateSettings,
) -> Result<DuplicateReport, ToolError> {
    let started = std::time::Instant::now();
    let (piece, mut report) = plan_patch(mesh, outline, layer, settings)?;
    report.layer = mesh.append(&piece);
    report.millis = started.elapsed().as_secs_f64() * 1e3;
    Ok(report)
}

fn bad(why: &str) -> ToolError {
    ToolError::BadStroke(format!("a patch's outline: {why}"))
}

/// The outline closed and resampled at about `edge`, without repeating its first point.
fn closed_ring(points: &[Vec3], edge: f32) -> Result<Vec<Vec3>, ToolError> {
    let gap = points[0].distance(points[points.len() - 1]);
    if gap > (CLOSING_SHARE * length(points)).max(2.0 * edge) {
        return Err(bad(&format!(
            "it is not closed (its ends are {:.1} edges apart)",
            gap / edge
        )));
    }
    let mut closed = points.to_vec();
    closed.push(points[0]);
    let around = perimeter(points);
    if around < 8.0 * edge {
        return Err(bad(&format!(
            "it is too short ({:.1} edges around; a patch needs at least 8 for four sides)",
            around / edge
        )));
    }
    let count = (around / edge).round() as usize;
    let mut ring = resample(&closed, count);
    ring.pop();
    Ok(ring)
}

/// `count + 1` points evenly spaced along the polyline `points` by arc length, both ends kept.
fn resample(points: &[Vec3], count: usize) -> Vec<Vec3> {
    let lengths: Vec<f32> = points.windows(2).map(|w| w[0].distance(w[1])).collect();
    let total: f32 = lengths.iter().sum();
    let mut out = Vec::with_capacity(count + 1);
    let (mut segment, mut walked) = (0, 0.0);
    for k in 0..=count {
        let at = total * k as f32 / count as f32;
        while segment + 1 < lengths.len() && walked + lengths[segment] < at {
            walked += lengths[segment];
            segment += 1;
        }
        let t = ((at - walked) / lengths[segment].max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
        out.push(points[segment].lerp(points[segment + 1], t));
    }
    out
}

/// The ring in the plane of its Newell normal; an error where it crosses itself (or winds
/// around no area at all).
fn flatten(ring: &[Vec3]) -> Result<Vec<Vec2>, ToolError> {
    let n = ring.len();
    let normal: Vec3 = (0..n).map(|i| ring[i].cross(ring[(i + 1) % n])).sum();
    let Some(normal) = normal.try_normalize() else {
        return Err(bad("it crosses itself (it encloses no area)"));
    };
    let u = normal.any_orthonormal_vector();
    let v = normal.cross(u);
    let flat: Vec<Vec2> = ring.iter().map(|p| Vec2::new(p.dot(u), p.dot(v))).collect();
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let (a, b) = (flat[i], flat[(i + 1) % n]);
            let (c, d) = (flat[j], flat[(j + 1) % n]);
            if segments_cross(a, b, c, d) {
                return Err(bad(&format!("it crosses itself (near its point {i})")));
            }
        }
    }
    Ok(flat)
}

fn segments_cross(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let side = |p: Vec2, q: Vec2, r: Vec2| (q - p).perp_dot(r - p);
    let (d1, d2) = (side(c, d, a), side(c, d, b));
    let (d3, d4) = (side(a, b, c), side(a, b, d));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// Four corner indices, ascending: the sharpest turns at least an eighth of the ring apart,
/// completed by halving the longest side where the outline has fewer.
fn corners(flat: &[Vec2]) -> [usize; 4] {
    let n = flat.len();
    let window = (n / 16).max(1);
    let at = |i: isize| flat[i.rem_euclid(n as isize) as usize];
    let turn: Vec<f32> = (0..n as isize)
        .map(|i| {
            let (a, b) = (
                at(i) - at(i - window as isize),
                at(i + window as isize) - at(i),
            );
            a.angle_to(b).abs()
        })
        .collect();
    let apart = |i: usize, j: usize| {
        let d = i.abs_diff(j);
        d.min(n - d)
    };
    let spacing = (n / 8).max(2);
    let mut order: Vec<usize> = (0..n).filter(|&i| turn[i] >= CORNER_TURN).collect();
    order.sort_by(|&a, &b| turn[b].total_cmp(&turn[a]).then(a.cmp(&b)));
    let mut chosen: Vec<usize> = Vec::new();
    for i in order {
        if chosen.len() < 4 && chosen.iter().all(|&c| apart(c, i) >= spacing) {
            chosen.push(i);
        }
    }
    if chosen.is_empty() {
        chosen.push(0);
    }
    while chosen.len() < 4 {
        chosen.sort_unstable();
        let k = chosen.len();
        let gap = |g: usize| (chosen[(g + 1) % k] + n - chosen[g] - 1) % n + 1;
        let longest = (0..k)
            .max_by_key(|&g| (gap(g), usize::MAX - g))
            .expect("a corner");
        chosen.push((chosen[longest] + gap(longest) / 2) % n);
    }
    chosen.sort_unstable();
    [chosen[0], chosen[1], chosen[2], chosen[3]]
}

/// The discrete Coons patch's points, row by row, rows √3/2·L apart. In a lattice, even rows
/// run on whole columns from side to side and odd rows halfway between them, so that the rows
/// make near-equilateral triangles; odd rows stop half a column short of the sides, so the
/// patch's rim zigzags up to half an edge inside the outline's left and right sides. In a
/// grid of quads every row runs on whole columns.
struct Grid {
    points: Vec<Vec3>,
    /// Where each row's points start in `points`, and one past the last row.
    row_starts: Vec<usize>,
}

fn coons_grid(ring: &[Vec3], corners: &[usize; 4], edge: f32, layout: Layout) -> Grid {
    let n = ring.len();
    let side = |k: usize| -> Vec<Vec3> {
        let (from, to) = (corners[k], corners[(k + 1) % 4]);
        let steps = (to + n - from) % n;
        (0..=steps).map(|s| ring[(from + s) % n]).collect()
    };
    let sides: Vec<Vec<Vec3>> = (0..4).map(side).collect();
    let coons = Coons::new(&sides, edge);
    // A round outline's middle is longer than its sides (a disc is 2r across, its quarter
    // arcs 1.57r long): counting from the sides alone stretches the middle out of the
    // remesher's band, and it would split a third of the patch. A lattice takes each count
    // from the longest of the two sides and the patch's middle curve between them.
    let curve_length = |point: &dyn Fn(f32) -> Vec3| {
        let samples: Vec<Vec3> = (0..=PROBE)
            .map(|k| point(k as f32 / PROBE as f32))
            .collect();
        length(&samples)
    };
    let (mut along, mut across) = (
        length(&sides[0]).max(length(&sides[2])),
        length(&sides[1]).max(length(&sides[3])),
    );
    if layout == Layout::Lattice {
        along = along.max(curve_length(&|u| coons.at(u, 0.5)));
        across = across.max(curve_length(&|v| coons.at(0.5, v)));
    }
    let columns = ((along / edge).round() as usize).max(1);
    let rows = ((across / (0.5 * 3f32.sqrt() * edge)).round() as usize).max(1);
    let mut grid = Grid {
        points: Vec::with_capacity((columns + 1) * (rows + 1)),
        row_starts: Vec::with_capacity(rows + 2),
    };
    for j in 0..=rows {
        grid.row_starts.push(grid.points.len());
        let (shift, count) = match (layout, j % 2) {
            (Layout::Lattice, 1) => (0.5, columns),
            _ => (0.0, columns + 1),
        };
        let v = j as f32 / rows as f32;
        for k in 0..count {
            let u = (k as f32 + shift) / columns as f32;
            grid.points.push(coons.at(u, v));
        }
    }
    grid.row_starts.push(grid.points.len());
    grid
}

/// The length of the closed polyline through `ring`.
fn perimeter(ring: &[Vec3]) -> f32 {
    length(ring) + ring[ring.len() - 1].distance(ring[0])
}

/// Steps a curve across the patch is measured in.
const PROBE: usize = 32;
/// Steps per edge length the sides are sampled in, for the patch to be read between samples.
const SIDE_STEPS_PER_EDGE: f32 = 4.0;

fn length(polyline: &[Vec3]) -> f32 {
    polyline.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// A discrete Coons patch between four sides, each sampled finely by arc length and read
/// between its samples.
struct Coons {
    bottom: Vec<Vec3>,
    right: Vec<Vec3>,
    top: Vec<Vec3>,
    left: Vec<Vec3>,
}

impl Coons {
    fn new(sides: &[Vec<Vec3>], edge: f32) -> Coons {
        let fine = |side: &[Vec3]| {
            let steps = ((length(side) / edge * SIDE_STEPS_PER_EDGE).ceil() as usize).max(1);
            resample(side, steps)
        };
        let (mut top, mut left) = (fine(&sides[2]), fine(&sides[3]));
        top.reverse();
        left.reverse();
        Coons {
            bottom: fine(&sides[0]),
            right: fine(&sides[1]),
            top,
            left,
        }
    }

    /// The point at `(u, v)` in `[0, 1]²`: the two ruled surfaces less the bilinear one.
    fn at(&self, u: f32, v: f32) -> Vec3 {
        let (bottom, top) = (along(&self.bottom, u), along(&self.top, u));
        let (left, right) = (along(&self.left, v), along(&self.right, v));
        let (p00, p10) = (self.bottom[0], self.bottom[self.bottom.len() - 1]);
        let (p01, p11) = (self.top[0], self.top[self.top.len() - 1]);
        let ruled = bottom * (1.0 - v) + top * v + left * (1.0 - u) + right * u;
        let corners =
            p00 * (1.0 - u) * (1.0 - v) + p10 * u * (1.0 - v) + p01 * (1.0 - u) * v + p11 * u * v;
        ruled - corners
    }
}

/// The point `t` of the way along evenly spaced `samples`.
fn along(samples: &[Vec3], t: f32) -> Vec3 {
    let at = t.clamp(0.0, 1.0) * (samples.len() - 1) as f32;
    let i = (at.floor() as usize).min(samples.len() - 2);
    samples[i].lerp(samples[i + 1], at - i as f32)
}

/// The grid's rows stitched into strips of triangles (each step along the shorter of the two
/// diagonals it could take: in the lattice's middle, the row whose next point comes first), as
/// a one-layer mesh facing the way the surface under it faces (`surface_normal` at a point).
fn triangulate(
    positions: Vec<Vec3>,
    grid: &Grid,
    settings: &DuplicateSettings,
    surface_normal: impl Fn(Vec3) -> Vec3,
) -> Result<Mesh, ToolError> {
    let mut faces = Vec::with_capacity(2 * positions.len());
    let d2 = |i: usize, j: usize| positions[i].distance_squared(positions[j]);
    for rows in grid.row_starts.windows(3) {
        let (lower, upper) = (rows[0]..rows[1], rows[1]..rows[2]);
        let (mut a, mut b) = (lower.start, upper.start);
        while a + 1 < lower.end || b + 1 < upper.end {
            let lower_first =
                b + 1 == upper.end || (a + 1 < lower.end && d2(a + 1, b) <= d2(a, b + 1));
            if lower_first {
                faces.push([a, a + 1, b].map(|v| v as u32));
                a += 1;
            } else {
                faces.push([a, b + 1, b].map(|v| v as u32));
                b += 1;
            }
        }
    }
    // Which way the surface faces, from a few dozen faces.
    let facing: f32 = faces
        .iter()
        .step_by((faces.len() / 64).max(1))
        .map(|&[a, b, c]| {
            let [pa, pb, pc] = [a, b, c].map(|v| positions[v as usize]);
            let under = surface_normal(pa);
            (pb - pa).cross(pc - pa).dot(under)
        })
        .sum();
    if facing < 0.0 {
        faces.iter_mut().for_each(|f| f.swap(1, 2));
    }
    let layers = vec![0; faces.len()];
    let mut piece = Mesh::new(positions, faces, layers, vec![settings.name.clone()])?;
    piece.set_layer_brdf(0, settings.material);
    Ok(piece)
}
