//! The deformation field of each brush at one dab (one stroke sample, or one step of it).

use glam::{Quat, Vec3};

use super::{Brush, BrushKind};

/// Share of the radius a draw/inflate moves per sample at full strength and pressure.
const DRAW_RATE: f32 = 0.1;
/// Share of the distance to the centre a pinch closes per sample at full strength.
const PINCH_RATE: f32 = 0.25;
/// Radians a twist turns per sample at full strength.
const TWIST_RATE: f32 = 0.5;

/// Where the brush is and how it is held, for one application.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DabFrame {
    pub center: Vec3,
    /// Unit brush normal (the surface normal under the brush, or the sample's own).
    pub normal: Vec3,
    /// Plane point for flatten: the weighted centroid under the brush.
    pub plane_point: Vec3,
    /// How far the brush centre moved since the previous sample (grab).
    pub motion: Vec3,
}

/// One application of a brush: the frame, the sample's pressure and the share of the sample's
/// effect this step carries (a sample is split into steps of at most one edge length).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dab {
    pub brush: Brush,
    pub frame: DabFrame,
    pub pressure: f32,
    /// `1 / steps`.
    pub share: f32,
}

/// The longest move any vertex can make under `dab`, where the brush's settings bound it: every
/// weight is at most 1, and every vertex it moves lies within its radius (a flatten's plane
/// point too, so no vertex stands farther than twice the radius from the plane). `None` for
/// smooth, whose move is the surface's (the distance to a one-ring's centroid).
pub fn move_bound(dab: &Dab) -> Option<f32> {
    let brush = &dab.brush;
    let amount = (brush.strength * dab.pressure * dab.share).abs();
    let radius = brush.radius;
    let bound = match brush.kind {
        BrushKind::Draw | BrushKind::Inflate | BrushKind::Deflate => amount * DRAW_RATE * radius,
        BrushKind::Grab | BrushKind::Sweep | BrushKind::SweepVolume => {
            dab.frame.motion.length() * dab.share
        }
        BrushKind::Flatten | BrushKind::Trim => 2.0 * radius * amount.min(1.0),
        BrushKind::Pinch => amount * PINCH_RATE * radius,
        BrushKind::Crease => amount * (DRAW_RATE + PINCH_RATE) * radius,
        // A turn by an angle moves a point by at most the angle times its distance to the axis.
        BrushKind::Twist => amount * TWIST_RATE * radius,
        BrushKind::Paint | BrushKind::Mask => 0.0,
        BrushKind::Smooth => return None,
    };
    Some(bound)
}

/// Displacement of a vertex at `position` with normal `vertex_normal`, weight `weight` (the
/// falloff at its distance, or its captured weight for grab) and `ring_centroid` (centroid of
/// its one-ring, for smooth).
#[inline]
pub fn displacement(
    dab: &Dab,
    position: Vec3,
    vertex_normal: Vec3,
    ring_centroid: Vec3,
    weight: f32,
) -> Vec3 {
    let brush = &dab.brush;
    let frame = &dab.frame;
    let amount = brush.strength * dab.pressure * weight * dab.share;
    let sign = brush.direction();
    let pinch = |p: Vec3| {
        let to_center = frame.center - p;
        let tangential = to_center - frame.normal * to_center.dot(frame.normal);
        tangential * PINCH_RATE
    };
    match brush.kind {
        BrushKind::Draw => frame.normal * (sign * amount * DRAW_RATE * brush.radius),
        BrushKind::Inflate | BrushKind::Deflate => {
            vertex_normal * (sign * amount * DRAW_RATE * brush.radius)
        }
        BrushKind::Grab | BrushKind::Sweep | BrushKind::SweepVolume => {
            frame.motion * (weight * dab.share)
        }
        BrushKind::Smooth => (ring_centroid - position) * amount.min(1.0),
        BrushKind::Flatten => {
            let height = (position - frame.plane_point).dot(frame.normal);
            let pull = if sign > 0.0 { -height } else { 0.5 * height };
            frame.normal * (pull * amount.min(1.0))
        }
        BrushKind::Trim => {
            let height = (position - frame.plane_point).dot(frame.normal);
            let standing = if sign > 0.0 {
                height.max(0.0)
            } else {
                height.min(0.0)
            };
            frame.normal * (-standing * amount.min(1.0))
        }
        BrushKind::Pinch => pinch(position) * (sign * amount),
        BrushKind::Crease => {
            -frame.normal * (sign * amount * DRAW_RATE * brush.radius) + pinch(position) * amount
        }
        BrushKind::Paint | BrushKind::Mask => Vec3::ZERO,
        BrushKind::Twist => {
            let angle = sign * amount * TWIST_RATE;
            let turned = Quat::from_axis_angle(frame.normal, angle) * (position - frame.center);
            frame.center + turned - position
        }
    }
}
