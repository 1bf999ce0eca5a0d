//! A dab's kernels: `select` (the brush's selection list), `brush_frame` (the frame's
//! fixed-point sums over it) and `deform` (target positions), with the `FALLOFF_*`, `BRUSH_*`
//! and `FRAME_*` codes of `wgsl/shared/brush.wgsl` and `wgsl/deform.wgsl`.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::brush::{BrushKind, Falloff};

/// Where a brush is and how its effect fades: all selection needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrushSphere {
    pub center: Vec3,
    pub radius: f32,
    pub falloff: Falloff,
}

/// `(FALLOFF_* code, blend exponent, blend plateau)` of a falloff, as
/// `wgsl/shared/brush.wgsl` reads them.
pub fn falloff_code(falloff: Falloff) -> (u32, u32, f32) {
    match falloff {
        Falloff::Blend { n, inner } => (0, n, inner),
        Falloff::Smooth => (1, 0, 0.0),
        Falloff::Sphere => (2, 0, 0.0),
        Falloff::Linear => (3, 0, 0.0),
    }
}

/// The `BRUSH_*` code of `wgsl/shared/brush.wgsl`.
pub fn brush_code(kind: BrushKind) -> u32 {
    match kind {
        BrushKind::Draw => 0,
        BrushKind::Inflate => 1,
        BrushKind::Deflate => 2,
        BrushKind::Grab => 3,
        BrushKind::Smooth => 4,
        BrushKind::Flatten => 5,
        BrushKind::Pinch => 6,
        BrushKind::Crease => 7,
        BrushKind::Twist => 8,
        BrushKind::Paint => 9,
        BrushKind::Mask => 10,
        BrushKind::Sweep => 11,
        BrushKind::SweepVolume => 12,
        BrushKind::Trim => 13,
    }
}

/// `SelectParams` in `wgsl/select.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct SelectParams {
    pub center: [f32; 3],
    pub radius: f32,
    /// Lowest cell of the brush's box.
    pub cell_min: [i32; 3],
    pub table_mask: u32,
    /// Size of the box in cells.
    pub cell_span: [u32; 3],
    pub inv_cell_size: f32,
    /// Cells in the box, or vertices when `scan_vertices` is set.
    pub candidate_count: u32,
    pub scan_vertices: u32,
    /// A `FALLOFF_*` code of `wgsl/shared/brush.wgsl`.
    pub falloff: u32,
    pub blend_n: u32,
    pub capacity: u32,
    pub layer_count: u32,
    /// How far any vertex may have moved since the table was built.
    pub drift: f32,
    /// Nonzero: leave out vertices marked as filed in the overlay table.
    pub skip_marked: u32,
    /// The blend's plateau, a share of the radius (`Falloff::Blend::inner`).
    pub blend_inner: f32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// `SelectedVertex` in `wgsl/select.wgsl`: one entry of the compacted selection.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct SelectedVertex {
    pub vertex: u32,
    pub weight: f32,
}

/// `DeformParams` in `wgsl/deform.wgsl`: one dab.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct DeformParams {
    pub center: [f32; 3],
    pub radius: f32,
    pub normal: [f32; 3],
    pub strength: f32,
    pub plane_point: [f32; 3],
    pub pressure: f32,
    pub motion: [f32; 3],
    pub share: f32,
    /// A `BRUSH_*` code of `wgsl/shared/brush.wgsl`.
    pub kind: u32,
    pub sign: f32,
    pub capacity: u32,
    /// `FRAME_*` flags ([`FRAME_NORMAL_FROM_SUMS`], [`FRAME_PLANE_FROM_SUMS`]): which of
    /// normal and plane point the kernel takes from `brush_frame`'s sums.
    pub frame: u32,
}

/// Which parts of the dab's frame `deform` takes from the sums (`DeformParams::frame`).
pub const FRAME_PLANE_FROM_SUMS: u32 = 1;
pub const FRAME_NORMAL_FROM_SUMS: u32 = 2;

/// `FrameParams` in `wgsl/brush_frame.wgsl`: where the brush is, and how much of the
/// selection list to sum.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct FrameParams {
    pub center: [f32; 3],
    pub inv_radius: f32,
    pub capacity: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// Words of `brush_frame`'s output: seven three-word sums (weight · normal x, y, z; weight ·
/// offset from the centre over the radius x, y, z; weight) and three spare.
pub const FRAME_SUM_WORDS: usize = 24;

/// `brush_frame`'s output.
pub type FrameSums = [u32; FRAME_SUM_WORDS];

/// The parameters of `brush_frame` for a brush at `center` of `radius` over a selection list
/// of `capacity` entries (the CPU mirror and the GPU host both build them here).
pub fn frame_params(center: Vec3, radius: f32, capacity: usize) -> FrameParams {
    FrameParams {
        center: center.to_array(),
        inv_radius: 1.0 / radius,
        capacity: capacity as u32,
        _pad0: 0,
        _pad1: 0,
        _pad2: 0,
    }
}
