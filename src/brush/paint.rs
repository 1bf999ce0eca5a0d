//! Painting reflectance (sLayer, "Reflectance Editing"): at each dab the BRDF of every vertex
//! under the brush becomes a weighted sum of its own BRDF and the brush's. Painting rides along
//! with any deformation brush in the same pass, or alone with the `paint` brush.

use std::sync::Arc;

use glam::Vec3;

use super::Stencil;
use crate::mesh::Brdf;

/// What a stroke paints.
#[derive(Debug, Clone, PartialEq)]
pub struct Paint {
    /// The brush's material (a stencil, when there is one, replaces it texel by texel).
    pub brdf: Brdf,
    pub stencil: Option<Arc<Stencil>>,
    /// Largest share of the brush BRDF one dab mixes in, at the brush centre and full pressure.
    pub opacity: f32,
}

impl Paint {
    /// A plain material at full opacity.
    pub fn material(brdf: Brdf) -> Paint {
        Paint {
            brdf,
            stencil: None,
            opacity: 1.0,
        }
    }

    /// The brush's BRDF at `position` under a brush with unit normal `normal`.
    pub fn brdf_at(&self, position: Vec3, normal: Vec3) -> Brdf {
        match &self.stencil {
            Some(stencil) => stencil.at(position, normal),
            None => self.brdf,
        }
    }
}

/// The share of the brush BRDF mixed into a vertex: falloff weight × pressure × opacity, in
/// [0, 1]. The painted BRDF is `old.lerp(brush, share)`, which stays between the two, field by
/// field, because the parametrization is linear.
#[inline]
pub fn paint_share(weight: f32, pressure: f32, opacity: f32) -> f32 {
    let share = weight * pressure * opacity;
    if share.is_nan() {
        0.0
    } else {
        share.clamp(0.0, 1.0)
    }
}
