//! Mirror of `wgsl/deform.wgsl`: `src/brush/field.rs::displacement` spelled out as the shader
//! computes it (the twist's quaternion product in glam's order), over the selection list.

use glam::Vec3;

use super::brush_frame::frame_from_sums;
use super::shared::invocations;
use crate::abi::{DeformParams, FrameSums, SelectedVertex};
use crate::geom;

const DRAW_RATE: f32 = 0.1;
const PINCH_RATE: f32 = 0.25;
const TWIST_RATE: f32 = 0.5;
/// What the kernel binds besides its parameters and output.
pub struct DeformInputs<'a> {
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub selected: &'a [SelectedVertex],
    pub selection_count: u32,
    /// Per vertex (start, length) of its row in `neighbours`.
    pub neighbour_rows: &'a [u32],
    pub neighbours: &'a [u32],
    /// `brush_frame`'s sums, read where `DeformParams::frame` asks.
    pub frame_sums: &'a FrameSums,
}

/// `ring_centroid` of `wgsl/deform.wgsl`: the neighbours' offsets from `p` summed order-free,
/// as the pipeline's `ring_centroid`.
fn ring_centroid(inputs: &DeformInputs<'_>, v: u32, p: Vec3) -> Vec3 {
    let start = inputs.neighbour_rows[2 * v as usize];
    let end = start + inputs.neighbour_rows[2 * v as usize + 1];
    if end == start {
        return p;
    }
    let offsets =
        || (start..end).map(|j| inputs.positions[inputs.neighbours[j as usize] as usize] - p);
    match geom::order_free_sum(offsets) {
        Some(sum) => p + sum / (end - start) as f32,
        None => p,
    }
}

fn pinch(params: &DeformParams, p: Vec3) -> Vec3 {
    let (center, normal) = (
        Vec3::from_array(params.center),
        Vec3::from_array(params.normal),
    );
    let to_center = center - p;
    let tangential = to_center - normal * to_center.dot(normal);
    tangential * PINCH_RATE
}

fn rotate(axis: Vec3, angle: f32, v: Vec3) -> Vec3 {
    let half = angle * 0.5;
    let b = axis * half.sin();
    let w = half.cos();
    let b2 = b.dot(b);
    v * (w * w - b2) + b * (v.dot(b) * 2.0) + b.cross(v) * (w * 2.0)
}

fn displacement(
    params: &DeformParams,
    inputs: &DeformInputs<'_>,
    v: u32,
    p: Vec3,
    weight: f32,
) -> Vec3 {
    let normal = Vec3::from_array(params.normal);
    let center = Vec3::from_array(params.center);
    let amount = params.strength * params.pressure * weight * params.share;
    let sign = params.sign;
    let lift = sign * amount * DRAW_RATE * params.radius;
    match params.kind {
        0 => normal * lift,
        1 | 2 => inputs.normals[v as usize] * lift,
        3 | 11 | 12 => Vec3::from_array(params.motion) * (weight * params.share),
        4 => (ring_centroid(inputs, v, p) - p) * amount.min(1.0),
        5 => {
            let height = (p - Vec3::from_array(params.plane_point)).dot(normal);
            let pull = if sign > 0.0 { -height } else { 0.5 * height };
            normal * (pull * amount.min(1.0))
        }
        6 => pinch(params, p) * (sign * amount),
        7 => -normal * lift + pinch(params, p) * amount,
        13 => {
            let height = (p - Vec3::from_array(params.plane_point)).dot(normal);
            let standing = if sign > 0.0 {
                height.max(0.0)
            } else {
                height.min(0.0)
            };
            normal * (-standing * amount.min(1.0))
        }
        8 => {
            let turned = rotate(normal, sign * amount * TWIST_RATE, p - center);
            center + turned - p
        }
        _ => Vec3::ZERO,
    }
}

/// `targets[i]` = where `selected[i]` moves.
pub fn deform(params: &DeformParams, inputs: &DeformInputs<'_>, targets: &mut [Vec3]) {
    // The shader resolves the frame per invocation; the same for each.
    let (normal, plane_point) = frame_from_sums(
        inputs.frame_sums,
        params.frame,
        (Vec3::from_array(params.center), params.radius),
        (
            Vec3::from_array(params.normal),
            Vec3::from_array(params.plane_point),
        ),
    );
    let params = &DeformParams {
        normal: normal.to_array(),
        plane_point: plane_point.to_array(),
        ..*params
    };
    for i in invocations(inputs.selection_count.min(params.capacity)) {
        let entry = inputs.selected[i as usize];
        let p = inputs.positions[entry.vertex as usize];
        let mut q = p + displacement(params, inputs, entry.vertex, p, entry.weight);
        if !q.is_finite() {
            q = p;
        }
        targets[i as usize] = q;
    }
}
