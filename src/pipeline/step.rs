//! One step of Algorithm 2 on the CPU, but for the collision response (`crate::collide`): the
//! brush frame, selection, deformation and paint, and how a sample's move splits into steps.
//! Each function is written once and runs either in parallel (rayon) or sequentially, and
//! either through the grids or by scanning everything (the reference); all four combinations
//! give bit-identical results, because every per-vertex result depends only on the state before
//! the step and reductions are taken in a fixed order.

use glam::Vec3;
use rayon::prelude::*;

use crate::abi::{SelectedVertex, frame_params};
use crate::brush::{Dab, DabFrame, Paint, displacement, paint_share};
use crate::collide::StrokeState;
use crate::cpu;
use crate::geom;
use crate::mesh::{Brdf, INVALID, Mesh, VertexFlags, partial_mask_factor};

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

/// Steps per sample are capped: a sample asking for more is a runaway brush. It moves this many
/// steps of at most `max_step` each, so short of its whole move, and is counted
/// ([`StrokeReport::capped_samples`](crate::pipeline::StrokeReport::capped_samples)).
pub const MAX_STEPS_PER_SAMPLE: usize = 256;

/// How a sample's move is split into steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepSplit {
    pub steps: usize,
    /// The share of the sample's whole move each step carries: `1 / steps`, less when capped.
    pub share: f32,
    /// The move needed more than [`MAX_STEPS_PER_SAMPLE`] steps.
    pub capped: bool,
}

/// The steps a sample whose longest move is `longest_move` takes, each of at most
/// `step_limit` (Algorithm 2 splits a motion so that no step crosses a layer).
pub fn steps_for(longest_move: f32, step_limit: f32) -> StepSplit {
    let needed = (longest_move / step_limit).ceil();
    if needed.is_nan() || needed <= 1.0 {
        return StepSplit {
            steps: 1,
            share: 1.0,
            capped: false,
        };
    }
    if needed > MAX_STEPS_PER_SAMPLE as f32 {
        return StepSplit {
            steps: MAX_STEPS_PER_SAMPLE,
            share: 1.0 / needed,
            capped: true,
        };
    }
    let steps = needed as usize;
    StepSplit {
        steps,
        share: 1.0 / steps as f32,
        capped: false,
    }
}

/// The longest move from each selected vertex's position in `mesh` to its target.
pub fn longest_move(mesh: &Mesh, selection: &[(u32, f32)], targets: &[Vec3]) -> f32 {
    selection
        .iter()
        .zip(targets)
        .map(|(&(v, _), q)| mesh.positions()[v as usize].distance(*q))
        .fold(0.0f32, f32::max)
}

/// Brush selection: active, unmasked vertices with positive falloff weight (less by a partial
/// mask), sorted by index.
pub fn select(state: &StrokeState<'_>, mesh: &Mesh, dab: &Dab) -> Vec<(u32, f32)> {
    within_brush(state, mesh, dab)
        .into_iter()
        .filter(|&v| selectable(state, mesh, v))
        .filter_map(|v| {
            let mut w = falloff_at(mesh, dab, v);
            if let Some(factor) = partial_mask_factor(mesh.flags()[v as usize].bits()) {
                w *= factor;
            }
            (w > 0.0).then_some((v, w))
        })
        .collect()
}

/// The mask brush's selection: vertices of active layers under the brush with their falloff
/// weights, masked ones included (it paints the mask), sorted by index.
pub fn select_for_mask(state: &StrokeState<'_>, mesh: &Mesh, dab: &Dab) -> Vec<(u32, f32)> {
    within_brush(state, mesh, dab)
        .into_iter()
        .filter(|&v| {
            state.active[mesh.vertex_layers()[v as usize] as usize]
                && !mesh.flags()[v as usize].contains(VertexFlags::DEAD)
        })
        .filter_map(|v| Some((v, falloff_at(mesh, dab, v))).filter(|&(_, w)| w > 0.0))
        .collect()
}

/// The brush's falloff weight at vertex `v`.
fn falloff_at(mesh: &Mesh, dab: &Dab, v: u32) -> f32 {
    let t = mesh.positions()[v as usize].distance(dab.frame.center) / dab.brush.radius;
    dab.brush.falloff.weight(t)
}

/// The live vertices within the brush's sphere, ascending.
fn within_brush(state: &StrokeState<'_>, mesh: &Mesh, dab: &Dab) -> Vec<u32> {
    let radius = dab.brush.radius;
    let center = dab.frame.center;
    let mut found = Vec::new();
    match state.grid {
        Some(grid) => grid.vertices_in_sphere(mesh.positions(), center, radius, &mut found),
        None => {
            let r2 = radius * radius;
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
}

/// On an active layer, not masked, alive.
pub fn selectable(state: &StrokeState<'_>, mesh: &Mesh, v: u32) -> bool {
    let flags = mesh.flags()[v as usize];
    state.active[mesh.vertex_layers()[v as usize] as usize]
        && !flags.intersects(VertexFlags::MASKED | VertexFlags::DEAD)
}

/// Centroid of a vertex's one-ring; on a boundary, of its two boundary neighbours, so open
/// sheets do not shrink from their rims. The offsets from the vertex are summed order-free
/// ([`geom::order_free_sum`]), so a mirrored ring gets the mirrored centroid to the bit.
fn ring_centroid(mesh: &Mesh, v: u32) -> Vec3 {
    let positions = mesh.positions();
    let p = positions[v as usize];
    let sum = if mesh.is_boundary_vertex(v) {
        let ring = mesh.neighbours(v);
        let ends = [ring[0], ring[ring.len() - 1]];
        geom::order_free_sum(|| ends.iter().map(|&u| positions[u as usize] - p)).map(|s| (s, 2))
    } else {
        let ring = || {
            mesh.adjacency()
                .corners_around(v)
                .map(|c| positions[mesh.corner_vertex(crate::mesh::next(c)) as usize] - p)
        };
        geom::order_free_sum(ring).map(|s| (s, ring().count()))
    };
    match sum {
        Some((sum, count)) if count > 0 => p + sum / count as f32,
        _ => p,
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
