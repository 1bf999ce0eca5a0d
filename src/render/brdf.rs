//! The preview's reflectance model, on the CPU: the reference that `wgsl/render/preview.wgsl`
//! mirrors line for line (sLayer, "Reflectance Editing": a microfacet BRDF with the Phong
//! distribution over a linear parametrization).
//!
//! A vertex's [`Brdf`] holds diffuse albedo `kd`, specular albedo `ks` (the Fresnel reflectance
//! at normal incidence) and a linearized roughness `r`. The model is Cook–Torrance:
//!
//! ```text
//! f(l, v) = kd/π + D(h)·G(l, v, h)·F(v·h) / (4 (n·l)(n·v))
//! ```
//!
//! with the normalized Blinn–Phong distribution `D`, Schlick's Fresnel `F` toward white at
//! grazing angles, and Cook and Torrance's V-cavity shadowing/masking term `G`, lit by two
//! directional lights and a sky-over-ground environment ([`Lighting`]).

use glam::Vec3;

use crate::mesh::Brdf;

pub use crate::mesh::{MIN_SLOPE, blinn_exponent};

/// The normalized Blinn–Phong distribution: `(e + 2)/(2π) · (n·h)^e`, integrating to one over
/// the projected hemisphere.
pub fn blinn_distribution(n_dot_h: f32, exponent: f32) -> f32 {
    (exponent + 2.0) / std::f32::consts::TAU * n_dot_h.max(0.0).powf(exponent)
}

/// Schlick's approximation of Fresnel reflectance from `f0` at normal incidence.
pub fn schlick_fresnel(f0: Vec3, v_dot_h: f32) -> Vec3 {
    let m = (1.0 - v_dot_h.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

/// Cook and Torrance's shadowing and masking of V-shaped microfacet grooves.
pub fn shadowing(n_dot_l: f32, n_dot_v: f32, n_dot_h: f32, v_dot_h: f32) -> f32 {
    let v_dot_h = v_dot_h.max(1e-4);
    let g = 2.0 * n_dot_h / v_dot_h;
    (g * n_dot_v).min(g * n_dot_l).min(1.0)
}

/// A directional light: unit direction toward the light, and its irradiance on a surface
/// facing it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    pub direction: Vec3,
    pub irradiance: Vec3,
}

/// The preview's lighting: a warm key light from the left of the view, about 40° above the
/// xy plane (raking enough to model sculpted relief), a cool, weaker fill from the right, and a
/// sky-over-ground environment (`+z` up) that lights diffuse surfaces softly and that glossy
/// ones reflect, so that bare metal looks like metal rather than black.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lighting {
    pub key: Light,
    pub fill: Light,
    /// Radiance of the environment straight up and straight down.
    pub sky: Vec3,
    pub ground: Vec3,
}

/// Share of the environment's radiance that reaches diffuse surfaces (it stands for the
/// occlusion a preview does not compute).
pub const AMBIENT_DIFFUSE: f32 = 0.3;

impl Lighting {
    /// Lights placed for a camera with image axes `right` and `up` looking from `toward` (unit
    /// direction from the target to the camera).
    pub fn for_view(right: Vec3, up: Vec3, toward: Vec3) -> Lighting {
        // The camera's side of the scene, on the ground plane.
        let front = Vec3::new(toward.x, toward.y, 0.0).normalize_or(-up);
        let key = (-right * 0.75 + front * 0.35 + Vec3::Z * 0.7).normalize();
        let fill = (right * 0.6 + front * 0.5 + Vec3::Z * 0.6).normalize();
        Lighting {
            key: Light {
                direction: key,
                irradiance: Vec3::new(2.7, 2.55, 2.35),
            },
            fill: Light {
                direction: fill,
                irradiance: Vec3::new(0.5, 0.58, 0.72),
            },
            sky: Vec3::new(0.55, 0.62, 0.75),
            ground: Vec3::new(0.13, 0.12, 0.11),
        }
    }

    /// Environment radiance in direction `d`, blurred toward its mean as `blur` goes to 1.
    pub fn environment(&self, d: Vec3, blur: f32) -> Vec3 {
        let sharp = self.ground.lerp(self.sky, 0.5 + 0.5 * d.z.clamp(-1.0, 1.0));
        sharp.lerp(0.5 * (self.ground + self.sky), blur.clamp(0.0, 1.0))
    }
}

/// Reflected radiance for unit irradiance from `l`: `f(l, v)·(n·l)`. All vectors are unit
/// length; `n` faces the viewer. Zero when the light is below the surface.
pub fn reflect(brdf: &Brdf, n: Vec3, l: Vec3, v: Vec3) -> Vec3 {
    let n_dot_l = n.dot(l);
    if n_dot_l <= 0.0 {
        return Vec3::ZERO;
    }
    let n_dot_v = n.dot(v).max(1e-4);
    let h = (l + v).normalize_or(n);
    let n_dot_h = n.dot(h).max(0.0);
    let v_dot_h = v.dot(h).max(0.0);
    let kd = Vec3::from_array(brdf.diffuse);
    let ks = Vec3::from_array(brdf.specular);
    let d = blinn_distribution(n_dot_h, blinn_exponent(brdf.roughness));
    let g = shadowing(n_dot_l, n_dot_v, n_dot_h, v_dot_h);
    let f = schlick_fresnel(ks, v_dot_h);
    let specular = f * (d * g / (4.0 * n_dot_l * n_dot_v));
    (kd / std::f32::consts::PI + specular) * n_dot_l
}

/// Light from the environment: diffuse from the hemisphere around `n`, specular reflected
/// about it, with Fresnel's rise at grazing angles damped for rough surfaces (which do not
/// mirror their surroundings even there).
pub fn environment_light(brdf: &Brdf, n: Vec3, v: Vec3, lighting: &Lighting) -> Vec3 {
    let kd = Vec3::from_array(brdf.diffuse);
    let ks = Vec3::from_array(brdf.specular);
    let r = brdf.roughness.clamp(0.0, 1.0);
    let n_dot_v = n.dot(v).clamp(0.0, 1.0);
    let mirrored = n * (2.0 * n.dot(v)) - v;
    let grazing = (1.0 - n_dot_v).powi(5);
    let fresnel = ks + (Vec3::splat(1.0 - r).max(ks) - ks) * grazing;
    // Diffuse light from the hemisphere is the environment fully blurred about the normal.
    let hemisphere = lighting
        .ground
        .lerp(lighting.sky, 0.5 + 0.5 * n.z.clamp(-1.0, 1.0));
    kd * hemisphere * AMBIENT_DIFFUSE + fresnel * lighting.environment(mirrored, r)
}

/// Radiance leaving a point toward the viewer under `lighting`, clamped to the displayable
/// range (the render target applies the sRGB curve).
pub fn shade(brdf: &Brdf, n: Vec3, v: Vec3, lighting: &Lighting) -> Vec3 {
    let n = if n.dot(v) < 0.0 { -n } else { n };
    let radiance = reflect(brdf, n, lighting.key.direction, v) * lighting.key.irradiance
        + reflect(brdf, n, lighting.fill.direction, v) * lighting.fill.irradiance
        + environment_light(brdf, n, v, lighting);
    radiance.clamp(Vec3::ZERO, Vec3::ONE)
}
