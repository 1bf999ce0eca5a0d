//! Per-vertex attributes that travel with the geometry: reflectance and flags.

use bytemuck::{Pod, Zeroable};

/// Index of a layer. Layers are labels on faces and vertices (docs/design.md, "Data"), not separate meshes.
pub type LayerId = u32;

/// A per-vertex BRDF in a linear parametrization: diffuse albedo, specular albedo and a linearized
/// roughness of a microfacet model with the Blinn–Phong distribution (after AppIm, Di Renzo et al.
/// 2014). Every field is meant to be blended linearly, so a weighted sum of two BRDFs is a
/// meaningful in-between material.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct Brdf {
    pub diffuse: [f32; 3],
    pub specular: [f32; 3],
    /// Linearized roughness in [0, 1]: 0 is a mirror, 1 is fully rough.
    pub roughness: f32,
}

impl Brdf {
    pub const fn new(diffuse: [f32; 3], specular: [f32; 3], roughness: f32) -> Self {
        Self {
            diffuse,
            specular,
            roughness,
        }
    }

    /// Neutral grey clay, the material of a vertex nobody has painted.
    pub const CLAY: Brdf = Brdf::new([0.6, 0.6, 0.6], [0.04, 0.04, 0.04], 0.6);

    pub fn as_array(&self) -> [f32; 7] {
        let [dr, dg, db] = self.diffuse;
        let [sr, sg, sb] = self.specular;
        [dr, dg, db, sr, sg, sb, self.roughness]
    }

    pub fn from_array(values: [f32; 7]) -> Self {
        Self::new(
            [values[0], values[1], values[2]],
            [values[3], values[4], values[5]],
            values[6],
        )
    }

    pub fn is_finite(&self) -> bool {
        self.as_array().iter().all(|v| v.is_finite())
    }

    /// `self + (other − self)·t`, field by field. The parametrization is linear, so this is the
    /// in-between material: painting, remeshing and the renderer's interpolation all use it.
    /// For `t` in [0, 1] every field stays between the two inputs' values.
    pub fn lerp(&self, other: &Brdf, t: f32) -> Brdf {
        let (a, b) = (self.as_array(), other.as_array());
        Brdf::from_array(std::array::from_fn(|k| a[k] + (b[k] - a[k]) * t))
    }

    /// Every field clamped into its range ([0, 1] for all of them); NaN becomes 0.
    pub fn clamped(&self) -> Brdf {
        Brdf::from_array(
            self.as_array()
                .map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) }),
        )
    }

    /// The Blinn–Phong exponent of this BRDF's roughness ([`blinn_exponent`]).
    pub fn blinn_exponent(&self) -> f32 {
        blinn_exponent(self.roughness)
    }

    /// Whether every field lies in [0, 1].
    pub fn in_range(&self) -> bool {
        self.as_array().iter().all(|v| (0.0..=1.0).contains(v))
    }
}

impl Default for Brdf {
    fn default() -> Self {
        Brdf::CLAY
    }
}

/// Smallest microfacet slope `α` a BRDF is rendered or exported with. A perfect mirror (`α = 0`) would need an
/// infinite exponent; at 0.03 the highlight is already far smaller than a pixel's worth of
/// normal variation on our meshes.
pub const MIN_SLOPE: f32 = 0.03;

/// The Blinn–Phong exponent of linearized roughness `roughness` in [0, 1].
///
/// The mapping is chosen so that equal steps of `r` look like equal steps of blur, which is what
/// makes a weighted sum of two BRDFs an in-between material (AppIm's requirement, Di Renzo et
/// al. 2014): the exponent itself is far from linear (a 50/50 mix of exponents 10 and 1000 is
/// a near-mirror, not a half-rough surface). We take the RMS microfacet slope `α = r²`, which
/// Burley (Disney, 2012) found to be perceptually linear, and turn it into the Blinn exponent
/// with Walter et al.'s (2007) match between Beckmann and Blinn–Phong, `e = 2/α² − 2`.
/// `r = 1` gives `e = 0`, a uniform distribution of microfacets; `r = 0` is clamped at
/// [`MIN_SLOPE`] (`e ≈ 2221`). Values outside [0, 1] are clamped.
pub fn blinn_exponent(roughness: f32) -> f32 {
    let r = if roughness.is_nan() {
        1.0
    } else {
        roughness.clamp(0.0, 1.0)
    };
    let alpha = (r * r).max(MIN_SLOPE);
    2.0 / (alpha * alpha) - 2.0
}

bitflags::bitflags! {
    /// Per-vertex state bits.
    #[repr(transparent)]
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Pod, Zeroable)]
    pub struct VertexFlags: u32 {
        /// Held in place by a collision during the current stroke.
        const LOCKED = 1;
        /// Protected by the user's mask: brushes never move it.
        const MASKED = 1 << 1;
        /// Deleted; removed by the next compaction.
        const DEAD = 1 << 2;
        /// A partial mask, 1 to 254 of 255 ([`VertexFlags::mask`]): brushes move the vertex
        /// that much less. Zero with `MASKED` clear is unmasked; a full mask is `MASKED`.
        const MASK_LEVEL = 0xff << 8;
    }
}

/// One step of a partial mask: levels are multiples of it.
const MASK_STEP: f32 = 1.0 / 255.0;

impl VertexFlags {
    /// The mask as a weight in [0, 1]: 0 unmasked, 1 fully masked (brushes never move it).
    pub fn mask(self) -> f32 {
        if self.contains(VertexFlags::MASKED) {
            1.0
        } else {
            self.mask_level() as f32 * MASK_STEP
        }
    }

    /// Sets the mask to `weight`, clamped into [0, 1] and rounded to 1/255 (NaN unmasks).
    pub fn set_mask(&mut self, weight: f32) {
        let level = if weight.is_nan() {
            0
        } else {
            (weight.clamp(0.0, 1.0) * 255.0).round() as u32
        };
        self.remove(VertexFlags::MASKED | VertexFlags::MASK_LEVEL);
        match level {
            0 => {}
            255 => self.insert(VertexFlags::MASKED),
            _ => *self |= VertexFlags::from_bits_retain(level << 8),
        }
    }

    /// The partial mask level, 0 to 254.
    fn mask_level(self) -> u32 {
        (self.bits() >> 8) & 0xff
    }

    /// The bits a file keeps (the mask); the others are the engine's own.
    pub const PERSISTENT: VertexFlags = VertexFlags::MASKED.union(VertexFlags::MASK_LEVEL);
}

/// What a brush's falloff weight is multiplied by at a vertex with flags `bits` (as the kernels
/// read them): `None` when no partial mask is set, so unmasked weights are not touched at all.
/// The same arithmetic as `wgsl/select.wgsl`: the level's complement times one step, both exact
/// in `f32`, one rounding.
pub fn partial_mask_factor(bits: u32) -> Option<f32> {
    let level = (bits >> 8) & 0xff;
    (level != 0).then(|| (255 - level) as f32 * MASK_STEP)
}
