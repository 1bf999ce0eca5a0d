//! Stencils: textures whose texels are whole BRDFs (sLayer: "the standard brush texturing
//! interface, which we augment with full BRDFs"), tiled over the surface and projected along the
//! brush normal.

use glam::Vec3;

use crate::mesh::Brdf;

/// A repeating texture of BRDFs.
#[derive(Debug, Clone, PartialEq)]
pub struct Stencil {
    width: usize,
    height: usize,
    /// Row-major, `width × height`.
    texels: Vec<Brdf>,
    /// World size of one repeat of the texture.
    pub tile: f32,
}

/// Generated stencil patterns of two materials.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pattern {
    /// A 2 × 2 checkerboard per tile.
    Checker,
    /// Two stripes per tile, along the tangent's v direction.
    Stripes,
    /// A round spot of the second material in the middle of each tile.
    Spots,
}

impl Pattern {
    pub const ALL: [Pattern; 3] = [Pattern::Checker, Pattern::Stripes, Pattern::Spots];

    pub fn name(self) -> &'static str {
        match self {
            Pattern::Checker => "checker",
            Pattern::Stripes => "stripes",
            Pattern::Spots => "spots",
        }
    }

    pub fn from_name(name: &str) -> Option<Pattern> {
        Pattern::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// Texels per side of a generated pattern.
const PATTERN_RESOLUTION: usize = 32;

/// sRGB-encoded 8-bit value to linear reflectance.
fn srgb_to_linear(value: u8) -> f32 {
    crate::material::srgb_to_linear(value as f32 / 255.0)
}

impl Stencil {
    /// A stencil from texels, row-major; `None` if the sizes disagree or it is empty.
    pub fn new(width: usize, height: usize, texels: Vec<Brdf>, tile: f32) -> Option<Stencil> {
        (width > 0 && height > 0 && texels.len() == width * height).then_some(Stencil {
            width,
            height,
            texels,
            tile,
        })
    }

    /// A generated pattern of `first` and `second`, one repeat per `tile` world units.
    pub fn pattern(pattern: Pattern, first: Brdf, second: Brdf, tile: f32) -> Stencil {
        let n = PATTERN_RESOLUTION;
        let texels = (0..n * n)
            .map(|i| {
                // Texel centres in [0, 1)².
                let u = ((i % n) as f32 + 0.5) / n as f32;
                let v = ((i / n) as f32 + 0.5) / n as f32;
                let second_here = match pattern {
                    Pattern::Checker => (u < 0.5) != (v < 0.5),
                    Pattern::Stripes => (u * 2.0).fract() >= 0.5,
                    Pattern::Spots => (u - 0.5).hypot(v - 0.5) < 0.3,
                };
                if second_here { second } else { first }
            })
            .collect();
        Stencil {
            width: n,
            height: n,
            texels,
            tile,
        }
    }

    /// A stencil from 8-bit RGBA pixels (rows top to bottom): RGB, decoded from sRGB, is the
    /// diffuse albedo; alpha is the linearized roughness (255 = fully rough, so an opaque image
    /// paints a matte material); the specular albedo, which a colour image does not carry, is
    /// `specular` for every texel.
    pub fn from_rgba(
        width: usize,
        height: usize,
        rgba: &[u8],
        specular: [f32; 3],
        tile: f32,
    ) -> Option<Stencil> {
        if rgba.len() != width * height * 4 {
            return None;
        }
        let texels = rgba
            .chunks_exact(4)
            .map(|p| {
                Brdf::new(
                    [
                        srgb_to_linear(p[0]),
                        srgb_to_linear(p[1]),
                        srgb_to_linear(p[2]),
                    ],
                    specular,
                    p[3] as f32 / 255.0,
                )
            })
            .collect();
        Stencil::new(width, height, texels, tile)
    }

    /// Decodes a PNG into a stencil (see [`Stencil::from_rgba`] for what the channels mean).
    pub fn from_png(bytes: &[u8], specular: [f32; 3], tile: f32) -> Result<Stencil, String> {
        let image = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
            .map_err(|e| e.to_string())?
            .into_rgba8();
        let (width, height) = (image.width() as usize, image.height() as usize);
        Stencil::from_rgba(width, height, image.as_raw(), specular, tile)
            .ok_or_else(|| "the image has no pixels".to_string())
    }

    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    fn texel(&self, x: i64, y: i64) -> Brdf {
        let x = x.rem_euclid(self.width as i64) as usize;
        let y = y.rem_euclid(self.height as i64) as usize;
        self.texels[y * self.width + x]
    }

    /// The BRDF at texture coordinates `(u, v)` (one repeat per unit, wrapping), bilinearly
    /// interpolated: a linear mix of BRDFs is a meaningful material.
    pub fn sample(&self, u: f32, v: f32) -> Brdf {
        let x = u * self.width as f32 - 0.5;
        let y = v * self.height as f32 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return self.texels[0];
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(&self.texel(x0 + 1, y0), fx);
        let bottom = self.texel(x0, y0 + 1).lerp(&self.texel(x0 + 1, y0 + 1), fx);
        top.lerp(&bottom, fy)
    }

    /// The BRDF the stencil puts at `position` for a brush with unit normal `normal`: the point
    /// is projected along the normal onto the plane through the origin perpendicular to it, and
    /// read in that plane's tangent frame (Duff et al.'s orthonormal basis, continuous in the
    /// normal; `+z` maps to the world's x and y). The stencil is anchored in the world rather than
    /// to the brush, so the dabs of one stroke continue one pattern instead of smearing it.
    pub fn at(&self, position: Vec3, normal: Vec3) -> Brdf {
        let (tangent, bitangent) = normal.any_orthonormal_pair();
        let tile = if self.tile > 0.0 { self.tile } else { 1.0 };
        self.sample(position.dot(tangent) / tile, position.dot(bitangent) / tile)
    }
}
