//! Brushes as deformation fields with a falloff (docs/design.md, "A stroke"), and strokes: polylines of samples
//! resampled at a spacing relative to the radius.

mod decode;
mod falloff;
mod field;
mod mirror;
mod paint;
mod resample;
mod stencil;
mod stroke;

pub use decode::{MAX_SAMPLES_PER_FILE, MAX_SAMPLES_PER_STROKE, MAX_STROKES};
pub use falloff::Falloff;
pub use field::{Dab, DabFrame, displacement, move_bound};
pub use mirror::{Mirror, SymmetrySpec};
pub use paint::{Paint, paint_share};
pub use resample::{DabLimit, MAX_DABS_PER_STROKE, Resampler, dabs_for, resample};
pub use stencil::{Pattern, Stencil};
pub use stroke::{
    LayerRef, MAX_BLEND_INNER, MAX_RADIUS_OVER_EXTENT, MAX_STENCIL_BYTES, PaintSpec, Sample,
    SampleSpec, StencilSpec, Stroke, StrokeError, StrokeFile, StrokeSettings, StrokeSpec,
};

use serde::{Deserialize, Serialize};

/// The deformation a brush applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BrushKind {
    /// Move along the brush normal (invert: push in).
    Draw,
    /// Move along each vertex normal (invert: deflate).
    Inflate,
    /// Inflate inverted.
    Deflate,
    /// Carry the vertices under the brush along with it.
    #[serde(alias = "move")]
    Grab,
    /// Move each vertex toward the centroid of its neighbours.
    Smooth,
    /// Move toward the plane fitted under the brush (invert: away from it).
    Flatten,
    /// Pull toward the brush centre in the brush plane (invert: push away).
    Pinch,
    /// Draw inward while pinching: a sharp groove (invert: a sharp ridge).
    Crease,
    /// Turn about the brush normal through the centre.
    Twist,
    /// Freestyle's sweep: what is under the brush at each sample moves with the brush's motion
    /// (the blend's plateau at full strength), so dragging off the surface draws it out.
    Sweep,
    /// Sweep whose closed layers keep their volume: what the sweep adds or takes is given back
    /// along the normals of the brush's flanks.
    #[serde(rename = "sweep-volume")]
    SweepVolume,
    /// Cut down to the plane fitted under the brush what stands above it (invert: fill up to
    /// it what lies below); unlike flatten, the other side is left alone.
    Trim,
    /// Move nothing; only paint the stroke's material (every brush can paint as it deforms).
    Paint,
    /// Move nothing; paint the mask with the falloff (invert: unmask). Masked vertices move
    /// less (fully masked: not at all) but still collide.
    Mask,
}

impl BrushKind {
    /// Every brush.
    pub const ALL: [BrushKind; 14] = [
        BrushKind::Draw,
        BrushKind::Inflate,
        BrushKind::Deflate,
        BrushKind::Grab,
        BrushKind::Smooth,
        BrushKind::Flatten,
        BrushKind::Pinch,
        BrushKind::Crease,
        BrushKind::Twist,
        BrushKind::Sweep,
        BrushKind::SweepVolume,
        BrushKind::Trim,
        BrushKind::Paint,
        BrushKind::Mask,
    ];

    /// The brushes that move vertices: all but the last two, `Paint` and `Mask`.
    pub const DEFORMING: &[BrushKind] = Self::ALL.split_at(Self::ALL.len() - 2).0;

    pub fn name(self) -> &'static str {
        match self {
            BrushKind::Draw => "draw",
            BrushKind::Inflate => "inflate",
            BrushKind::Deflate => "deflate",
            BrushKind::Grab => "grab",
            BrushKind::Smooth => "smooth",
            BrushKind::Flatten => "flatten",
            BrushKind::Pinch => "pinch",
            BrushKind::Crease => "crease",
            BrushKind::Twist => "twist",
            BrushKind::Sweep => "sweep",
            BrushKind::SweepVolume => "sweep-volume",
            BrushKind::Trim => "trim",
            BrushKind::Paint => "paint",
            BrushKind::Mask => "mask",
        }
    }

    /// Whether the brush moves vertices (all but `paint` and `mask`).
    pub fn deforms(self) -> bool {
        !matches!(self, BrushKind::Paint | BrushKind::Mask)
    }

    /// Whether the brush moves what it holds along with the pointer, through space (grab and
    /// the sweeps), rather than acting on the surface under the pointer; such a stroke
    /// stretches the surface and is remeshed between its samples where it did.
    pub fn drags(self) -> bool {
        matches!(
            self,
            BrushKind::Grab | BrushKind::Sweep | BrushKind::SweepVolume
        )
    }
}

/// A brush: what it does, how big and how strong, and how its effect fades.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Brush {
    pub kind: BrushKind,
    /// World units.
    pub radius: f32,
    /// In [0, 1]: 1 moves a vertex under the centre by a tenth of the radius per sample (draw,
    /// inflate), relaxes it fully (smooth, flatten) or turns it by half a radian (twist).
    pub strength: f32,
    pub falloff: Falloff,
    pub invert: bool,
}

impl Brush {
    /// +1, or −1 when inverted (deflate is inflate inverted).
    pub fn direction(&self) -> f32 {
        let inverted = self.invert ^ (self.kind == BrushKind::Deflate);
        if inverted { -1.0 } else { 1.0 }
    }
}
