//! Named materials: the BRDF each generated layer starts with, and the presets a painter picks.

use crate::mesh::Brdf;

/// A named BRDF preset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    pub name: &'static str,
    pub brdf: Brdf,
}

const fn material(
    name: &'static str,
    diffuse: [f32; 3],
    specular: f32,
    roughness: f32,
) -> Material {
    Material {
        name,
        brdf: Brdf::new(diffuse, [specular, specular, specular], roughness),
    }
}

pub const CLAY: Material = Material {
    name: "clay",
    brdf: Brdf::CLAY,
};
pub const PLASTER: Material = material("plaster", [0.86, 0.84, 0.78], 0.03, 0.85);
pub const PAINT: Material = material("paint", [0.24, 0.47, 0.58], 0.08, 0.35);
pub const RED_PAINT: Material = material("red-paint", [0.50, 0.07, 0.05], 0.08, 0.3);
pub const PEELING_PAINT: Material = material("peeling-paint", [0.78, 0.66, 0.42], 0.06, 0.45);
pub const WOOD: Material = material("wood", [0.74, 0.56, 0.36], 0.04, 0.7);
pub const INNER_BARK: Material = material("inner-bark", [0.46, 0.29, 0.17], 0.03, 0.8);
pub const BARK: Material = material("bark", [0.29, 0.23, 0.18], 0.03, 0.9);
pub const LICHEN: Material = material("lichen", [0.55, 0.62, 0.42], 0.02, 0.95);
pub const BARE_METAL: Material = Material {
    name: "bare-metal",
    brdf: Brdf::new([0.08, 0.08, 0.09], [0.62, 0.62, 0.64], 0.25),
};
pub const RUST: Material = material("rust", [0.44, 0.19, 0.07], 0.03, 0.85);
pub const RUST_FLAKE: Material = material("rust-flake", [0.58, 0.30, 0.12], 0.04, 0.75);

/// Every preset, for lookups by name.
pub const PRESETS: &[Material] = &[
    CLAY,
    PLASTER,
    PAINT,
    RED_PAINT,
    PEELING_PAINT,
    WOOD,
    INNER_BARK,
    BARK,
    LICHEN,
    BARE_METAL,
    RUST,
    RUST_FLAKE,
];

/// The preset called `name`, if any.
pub fn preset(name: &str) -> Option<Material> {
    PRESETS.iter().copied().find(|m| m.name == name)
}

/// The sRGB transfer function's inverse.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB transfer function.
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}
