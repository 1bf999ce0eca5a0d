//! Falloff curves: how a brush's effect fades from its centre (`t = 0`) to its rim (`t = 1`).

use serde::{Deserialize, Serialize};

/// A falloff curve. Every curve is 1 at the centre and 0 at and beyond the rim.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "curve", rename_all = "lowercase")]
pub enum Falloff {
    /// Freestyle's blend `b(t) = (1 − tⁿ)ⁿ` with an integer `n > 2`: zero slope at both the
    /// centre and the rim, so deformed and untouched regions meet smoothly; larger `n` widens
    /// the plateau. (The fragments of the Freestyle paper we have lose the formula; this form has
    /// the properties the text states.) `inner` is the share of the radius held at full
    /// strength, Freestyle's `R_i / R_o`: the curve runs over `[inner, 1]` instead of `[0, 1]`.
    Blend {
        n: u32,
        #[serde(default)]
        inner: f32,
    },
    /// `1 − (3t² − 2t³)`: smooth at both ends, like the usual sculpting default.
    Smooth,
    /// `√(1 − t²)`: a hemisphere, full in the middle and steep at the rim.
    Sphere,
    /// `1 − t`.
    Linear,
}

impl Default for Falloff {
    fn default() -> Self {
        Falloff::blend(3)
    }
}

impl Falloff {
    /// The blend of exponent `n` with no plateau (`inner` 0).
    pub const fn blend(n: u32) -> Self {
        Falloff::Blend { n, inner: 0.0 }
    }

    /// The weight at normalized distance `t = distance / radius`.
    #[inline]
    pub fn weight(&self, t: f32) -> f32 {
        // NaN and everything past the rim weigh nothing.
        if t.is_nan() || t >= 1.0 {
            return 0.0;
        }
        let t = t.max(0.0);
        match *self {
            Falloff::Blend { n, inner } => {
                if t <= inner {
                    return 1.0;
                }
                let t = (t - inner) / (1.0 - inner);
                let n = n as i32;
                (1.0 - t.powi(n)).powi(n)
            }
            Falloff::Smooth => 1.0 - t * t * (3.0 - 2.0 * t),
            Falloff::Sphere => (1.0 - t * t).sqrt(),
            Falloff::Linear => 1.0 - t,
        }
    }

    /// Short name for tables and logs.
    pub fn name(&self) -> String {
        match self {
            Falloff::Blend { n, inner } if *inner > 0.0 => format!("blend(n={n}, inner={inner})"),
            Falloff::Blend { n, .. } => format!("blend(n={n})"),
            Falloff::Smooth => "smooth".into(),
            Falloff::Sphere => "sphere".into(),
            Falloff::Linear => "linear".into(),
        }
    }
}
