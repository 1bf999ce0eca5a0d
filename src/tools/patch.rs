//! A new layer from a closed stroke (sLayer, "Editing Tools": "draw a closed stroke onto a
//! surface and create a new layer from it using discrete coons patches"): the outline is
//! projected onto the layer it is drawn on and resampled at `L`, split into four sides at its
//! sharpest corners (or evenly, where it has none), filled with a discrete Coons patch,
//! the patch's points projected onto the surface, and the whole lifted off it like a
//! duplicate: along the normals, clear of everything, remeshed to `L`, checked exactly.

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
    let bounds = Aabb::of_points(outline);
    let reach = (4.0 * edge).max(0.5 * (bounds.max - bounds.min).length());
    let surface = Obstacles::near(mesh, bounds.expanded(reach + edge), 1.5 * edge);
    // Most points lie near the surface: a short look first, the long one only where it fails.
    let near = 4.0 * edge;
    let nearest = |p: Vec3| {
        surface
            .nearest_face(p, near, layer)
            .or_else(|| surface.nearest_face(p, reach, layer))
    };
    let on_layer = |p: Vec3| nearest(p).map(|(_, q)| q);
    let projected: Vec<Vec3> = outline
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            on_layer(p).ok_or_else(|| bad(&format!("point {i} is not over layer {layer}")))
        })
        .collect::<Result<_, _>>()?;
    let ring = closed_ring(&projected, edge)?;
    let flat = flatten(&ring)?;
    let corners = corners(&flat);
    let grid = coons_grid(&ring, &corners, edge);
    // Each point on its own: a big patch's projection would otherwise leave cores idle.
    let positions = grid
        .points
        .par_iter()
        .map(|&p| on_layer(p).ok_or_else(|| bad("it encloses a hole in the layer")))
        .collect::<Result<Vec<Vec3>, _>>()?;
    let facing = |p: Vec3| nearest(p).map_or(Vec3::ZERO, |(f, _)| mesh.face_normal(f as usize));
    let piece = triangulate(positions, &grid, settings, facing)?;
    lift_off(mesh, piece, layer, settings)
}

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
    let perimeter: f32 = points.windows(2).map(|w| w[0].distance(w[1])).sum();
    let gap = points[0].distance(points[points.len() - 1]);
    if gap > (CLOSING_SHARE * perimeter).max(2.0 * edge) {
        return Err(bad(&format!(
            "it is not closed (its ends are {:.1} edges apart)",
            gap / edge
        )));
    }
    let mut closed = points.to_vec();
    closed.push(points[0]);
    let length = perimeter + gap;
    if length < 8.0 * edge {
        return Err(bad(&format!(
            "it is too short ({:.1} edges around; a patch needs at least 8 for four sides)",
            length / edge
        )));
    }
    let count = (length / edge).round() as usize;
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

/// The discrete Coons patch's points, row by row (`columns + 1` a row, `rows + 1` rows).
struct Grid {
    points: Vec<Vec3>,
    columns: usize,
    rows: usize,
}

fn coons_grid(ring: &[Vec3], corners: &[usize; 4], edge: f32) -> Grid {
    let n = ring.len();
    let side = |k: usize| -> Vec<Vec3> {
        let (from, to) = (corners[k], corners[(k + 1) % 4]);
        let steps = (to + n - from) % n;
        (0..=steps).map(|s| ring[(from + s) % n]).collect()
    };
    let length = |s: &[Vec3]| s.windows(2).map(|w| w[0].distance(w[1])).sum::<f32>();
    let sides: Vec<Vec<Vec3>> = (0..4).map(side).collect();
    let columns = ((length(&sides[0]).max(length(&sides[2])) / edge).round() as usize).max(1);
    // Rows √3/2·L apart: each quad's diagonal is then about 1.32·L, inside the remesher's
    // band (4/3·L), and its triangles near equilateral, so remeshing has little left to do.
    let row = 0.5 * 3f32.sqrt() * edge;
    let rows = ((length(&sides[1]).max(length(&sides[3])) / row).round() as usize).max(1);
    let bottom = resample(&sides[0], columns);
    let right = resample(&sides[1], rows);
    let mut top = resample(&sides[2], columns);
    top.reverse();
    let mut left = resample(&sides[3], rows);
    left.reverse();
    let (p00, p10, p01, p11) = (bottom[0], bottom[columns], top[0], top[columns]);
    let mut points = Vec::with_capacity((columns + 1) * (rows + 1));
    for j in 0..=rows {
        let v = j as f32 / rows as f32;
        for i in 0..=columns {
            let u = i as f32 / columns as f32;
            let ruled = bottom[i] * (1.0 - v) + top[i] * v + left[j] * (1.0 - u) + right[j] * u;
            let corners = p00 * (1.0 - u) * (1.0 - v)
                + p10 * u * (1.0 - v)
                + p01 * (1.0 - u) * v
                + p11 * u * v;
            points.push(ruled - corners);
        }
    }
    Grid {
        points,
        columns,
        rows,
    }
}

/// The grid's quads, each split along its shorter diagonal, as a one-layer mesh facing the
/// way the surface under it faces (`surface_normal` at a point).
fn triangulate(
    positions: Vec<Vec3>,
    grid: &Grid,
    settings: &DuplicateSettings,
    surface_normal: impl Fn(Vec3) -> Vec3,
) -> Result<Mesh, ToolError> {
    let at = |i: usize, j: usize| (j * (grid.columns + 1) + i) as u32;
    let mut faces = Vec::with_capacity(2 * grid.columns * grid.rows);
    for j in 0..grid.rows {
        for i in 0..grid.columns {
            let [a, b, c, d] = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            let p = |v: u32| positions[v as usize];
            if p(a).distance_squared(p(c)) <= p(b).distance_squared(p(d)) {
                faces.extend([[a, b, c], [a, c, d]]);
            } else {
                faces.extend([[a, b, d], [b, c, d]]);
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
