//! Strokes and the stroke file.
//!
//! A stroke file is JSON:
//!
//! ```json
//! {
//!   "version": 1,
//!   "strokes": [{
//!     "brush": "draw",            // draw inflate deflate grab (or move) smooth flatten pinch crease twist
//!     "radius": 0.03,             // world units
//!     "strength": 0.5,            // 0..1
//!     "falloff": {"curve": "blend", "n": 3},   // or {"curve": "smooth" | "sphere" | "linear"}
//!     "invert": false,
//!     "layers": [1, "flakes"],    // active layers, by index or name; the others stay still but collide
//!     "spacing": 0.25,            // resampling step, as a share of the radius
//!     "paint": {"material": "rust"},          // optional: paint while deforming (see below)
//!     "samples": [{"position": [0.5, 0.5, 0.01], "pressure": 1.0, "normal": [0, 0, 1]}]
//!   }]
//! }
//! ```
//!
//! `falloff`, `invert`, `spacing`, `paint`, `pressure` and `normal` may be left out (blend n=3,
//! false, 0.25, no paint, 1, the surface normal under the brush). Every problem is reported with
//! the stroke and sample it is in.
//!
//! `paint` makes any brush paint as it deforms; the `paint` brush only paints and needs it. At
//! each dab a vertex's BRDF becomes `old + (brush − old)·w·pressure·opacity`, `w` its falloff
//! weight (for the `paint` brush, `strength` multiplies the opacity too):
//!
//! ```json
//! "paint": {"material": "rust"}                                   // a preset (crate::material)
//! "paint": {"diffuse": [0.5, 0.2, 0.1], "specular": [0.04, 0.04, 0.04], "roughness": 0.7}
//! "paint": {"material": "paint", "roughness": 0.2, "opacity": 0.5} // a preset, overridden
//! "paint": {"material": "rust", "stencil": {"pattern": "spots", "with": "bare-metal", "tile": 0.05}}
//! "paint": {"material": "rust", "stencil": {"png": "moss.png", "tile": 0.1}}
//! ```
//!
//! A stencil replaces the material texel by texel, tiled every `tile` world units and projected
//! along the brush normal ([`super::Stencil::at`]). Patterns (`checker`, `stripes`, `spots`)
//! mix `material` and `with` (default `clay`); a PNG (path relative to the working directory)
//! gives diffuse albedo from its RGB, roughness from its alpha and the material's specular
//! albedo.

use glam::Vec3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use std::sync::Arc;

use super::decode::MAX_SAMPLES_PER_STROKE;
use super::{Brush, BrushKind, Falloff, Mirror, Paint, Pattern, Stencil, SymmetrySpec};
use crate::files::escape;
use crate::material;
use crate::mesh::{Brdf, LayerId, MAX_COORDINATE, Mesh};

/// A radius beyond this many times the mesh's bounding-box diagonal is rejected: such a brush
/// covers the whole mesh from anywhere on it, and brushes that move in proportion to their
/// radius (draw, inflate, crease) would move it by a fifth of its size per sample (a crease of
/// 5× the diagonal crushed a 5K-face sphere for over ten minutes).
pub const MAX_RADIUS_OVER_EXTENT: f32 = 2.0;

/// The largest plateau a blend falloff may have (`Falloff::Blend::inner`): past it the blend
/// is a step, and its rim a cliff.
pub const MAX_BLEND_INNER: f32 = 0.95;
/// The largest stencil PNG read (256 MiB): a texture, not a photograph archive.
pub const MAX_STENCIL_BYTES: u64 = 256 << 20;
/// A radius below this share of the mean edge length touches nothing and is rejected.
const MIN_RADIUS_OVER_EDGE: f32 = 0.05;

#[derive(Debug, Error)]
pub enum StrokeError {
    #[error("{source_name}:{line}:{column}: {message}")]
    Json {
        source_name: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{source_name}: {location}: {message}")]
    Invalid {
        source_name: String,
        location: String,
        message: String,
    },
}

/// A layer named in a stroke file: by index or by name.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum LayerRef {
    Index(u32),
    Name(String),
}

fn one() -> f32 {
    1.0
}

pub(super) fn default_spacing() -> f32 {
    0.25
}

fn version_one() -> u32 {
    1
}

/// One sample as written in the file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SampleSpec {
    pub position: [f32; 3],
    #[serde(default = "one")]
    pub pressure: f32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f32; 3]>,
}

/// The `paint` of a stroke as written in the file.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaintSpec {
    /// A preset's name; the fields below override its values.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diffuse: Option<[f32; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specular: Option<[f32; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roughness: Option<f32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub opacity: Option<f32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stencil: Option<StencilSpec>,
}

impl PaintSpec {
    /// A preset, as is.
    pub fn material(name: &str) -> PaintSpec {
        PaintSpec {
            material: Some(name.to_string()),
            ..PaintSpec::default()
        }
    }
}

/// A stencil as written in the file: a generated `pattern` or a `png`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StencilSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pattern: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub png: Option<String>,
    /// The pattern's second material (a preset name).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub with: Option<String>,
    /// World size of one repeat.
    pub tile: f32,
}

/// One stroke as written in the file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrokeSpec {
    pub brush: BrushKind,
    pub radius: f32,
    pub strength: f32,
    #[serde(default)]
    pub falloff: Falloff,
    #[serde(default)]
    pub invert: bool,
    pub layers: Vec<LayerRef>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub paint: Option<PaintSpec>,
    #[serde(default = "default_spacing")]
    pub spacing: f32,
    /// Brush every sample and its image across this plane too.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub symmetry: Option<SymmetrySpec>,
    pub samples: Vec<SampleSpec>,
}

/// A stroke file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrokeFile {
    #[serde(default = "version_one")]
    pub version: u32,
    pub strokes: Vec<StrokeSpec>,
    /// Layers whose policy is fuse (`topology::ProximityPolicy`) while the file is applied, by
    /// index or name; the others keep theirs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fuse: Vec<LayerRef>,
}

/// A stroke sample, checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub position: Vec3,
    pub pressure: f32,
    pub normal: Option<Vec3>,
}

/// A checked stroke, ready for a pipeline.
#[derive(Debug, Clone, PartialEq)]
pub struct Stroke {
    pub brush: Brush,
    /// What the stroke paints, if anything.
    pub paint: Option<Paint>,
    /// Active layers, sorted.
    pub layers: Vec<LayerId>,
    /// Resampling step as a share of the radius.
    pub spacing: f32,
    /// Every sample brushed with its image across this plane, in the same steps.
    pub symmetry: Option<Mirror>,
    pub samples: Vec<Sample>,
}

/// What a stroke is but its samples, which stream in while it is drawn
/// (`Pipeline::begin_stroke`).
#[derive(Debug, Clone, PartialEq)]
pub struct StrokeSettings {
    pub brush: Brush,
    pub paint: Option<Paint>,
    /// Active layers, sorted.
    pub layers: Vec<LayerId>,
    /// Resampling step as a share of the radius.
    pub spacing: f32,
    /// Every sample brushed with its image across this plane, in the same steps.
    pub symmetry: Option<Mirror>,
    /// Layers among `layers` whose policy is fuse (`topology::ProximityPolicy`): where the
    /// stroke leaves one touching itself, it joins or splits after the stroke. Sorted.
    pub fuse: Vec<LayerId>,
}

impl StrokeSettings {
    /// The arc length between resampled samples.
    pub fn resampling_step(&self) -> f32 {
        self.spacing * self.brush.radius
    }

    /// The brush checks a stroke file gets, for settings built in code (the app's): a radius
    /// that is a positive length no more than [`MAX_RADIUS_OVER_EXTENT`] times `extent` (the
    /// mesh's bounding-box diagonal), strength in [0, 1], spacing in [0.01, 2], a blend's `n`
    /// in 3..=16. The error names the field and says what is wrong with it.
    pub fn check(&self, extent: f32) -> Result<(), String> {
        let brush = &self.brush;
        check_brush(
            (brush.radius, brush.strength, self.spacing, brush.falloff),
            extent,
        )
        .map_err(|(field, message)| format!("brush{field}: {message}"))
    }
}

impl Stroke {
    /// The stroke without its samples.
    pub fn settings(&self) -> StrokeSettings {
        StrokeSettings {
            brush: self.brush,
            paint: self.paint.clone(),
            layers: self.layers.clone(),
            spacing: self.spacing,
            symmetry: self.symmetry,
            fuse: Vec::new(),
        }
    }
}

impl StrokeFile {
    /// Parses JSON; `source_name` names the file in messages.
    pub fn parse(text: &str, source_name: &str) -> Result<StrokeFile, StrokeError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| StrokeError::Json {
                source_name: source_name.to_string(),
                line: e.line(),
                column: e.column(),
                message: if e.is_eof() {
                    "the file ends before its JSON is complete".into()
                } else {
                    "not valid JSON here (a stroke file is one JSON object; docs/strokes.md)".into()
                },
            })?;
        let invalid = |(location, message): (String, String)| StrokeError::Invalid {
            source_name: source_name.to_string(),
            location: if location.is_empty() {
                "the file".into()
            } else {
                location
            },
            message,
        };
        let file = super::decode::file(&value).map_err(invalid)?;
        if file.version != 1 {
            return Err(invalid((
                "version".into(),
                format!("version {} is not supported (expected 1)", file.version),
            )));
        }
        Ok(file)
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The layers the file's `fuse` names, checked against `mesh`.
    pub fn fuse_layers(&self, mesh: &Mesh, source_name: &str) -> Result<Vec<LayerId>, StrokeError> {
        if self.fuse.is_empty() {
            return Ok(Vec::new());
        }
        resolve_layers(&self.fuse, mesh, "fuse").map_err(|(location, message)| {
            StrokeError::Invalid {
                source_name: source_name.to_string(),
                location,
                message,
            }
        })
    }

    /// Checks every stroke against `mesh` and resolves layer names.
    pub fn resolve(&self, mesh: &Mesh, source_name: &str) -> Result<Vec<Stroke>, StrokeError> {
        let extent = mesh.extent().unwrap_or(0.0).max(f32::MIN_POSITIVE);
        let edge = mesh.mean_edge_length();
        self.strokes
            .iter()
            .enumerate()
            .map(|(i, spec)| {
                let invalid = |location: String, message: String| StrokeError::Invalid {
                    source_name: source_name.to_string(),
                    location,
                    message,
                };
                resolve_stroke(spec, mesh, extent, edge)
                    .map_err(|(field, message)| invalid(format!("strokes[{i}]{field}"), message))
            })
            .collect()
    }
}

/// What is wrong with a brush's radius, strength, spacing and falloff on a mesh whose
/// bounding-box diagonal is `extent`, as the field (`.radius`, ...) and a message: the checks a
/// stroke file and [`StrokeSettings::check`] share.
fn check_brush(
    (radius, strength, spacing, falloff): (f32, f32, f32, Falloff),
    extent: f32,
) -> Result<(), (&'static str, String)> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err((".radius", format!("{radius} is not a positive length")));
    }
    if radius > MAX_RADIUS_OVER_EXTENT * extent {
        return Err((
            ".radius",
            format!(
                "{radius} is more than {MAX_RADIUS_OVER_EXTENT} times the mesh's size ({extent}): it would cover the whole mesh from anywhere on it"
            ),
        ));
    }
    if !(0.0..=1.0).contains(&strength) {
        return Err((".strength", format!("{strength} is outside [0, 1]")));
    }
    if !(0.01..=2.0).contains(&spacing) {
        return Err((
            ".spacing",
            format!("{spacing} is outside [0.01, 2] (a share of the radius)"),
        ));
    }
    if let Falloff::Blend { inner, .. } = falloff
        && !(0.0..=MAX_BLEND_INNER).contains(&inner)
    {
        return Err((
            ".falloff.inner",
            format!(
                "{inner} is outside [0, {MAX_BLEND_INNER}] (the share of the radius at full strength)"
            ),
        ));
    }
    if let Falloff::Blend { n, .. } = falloff
        && !(3..=16).contains(&n)
    {
        return Err((
            ".falloff.n",
            format!("{n} is outside 3..=16 (the blend needs n > 2)"),
        ));
    }
    Ok(())
}

/// A field's path (from the stroke) and what is wrong with it.
type FieldError = (String, String);

fn resolve_stroke(
    spec: &StrokeSpec,
    mesh: &Mesh,
    extent: f32,
    edge: f32,
) -> Result<Stroke, FieldError> {
    let fail = |field: &str, message: String| Err((field.to_string(), message));
    let brush = (spec.radius, spec.strength, spec.spacing, spec.falloff);
    check_brush(brush, extent).map_err(|(field, message)| (field.to_string(), message))?;
    if spec.radius < MIN_RADIUS_OVER_EDGE * edge {
        return fail(
            ".radius",
            format!(
                "{} is far below the mean edge length {edge}: it would touch nothing",
                spec.radius
            ),
        );
    }
    let samples = resolve_samples(&spec.samples)?;
    let layers = resolve_layers(&spec.layers, mesh, ".layers")?;
    let paint = resolve_stroke_paint(spec)?;
    Ok(Stroke {
        paint,
        brush: Brush {
            kind: spec.brush,
            radius: spec.radius,
            strength: spec.strength,
            falloff: spec.falloff,
            invert: spec.invert,
        },
        layers,
        spacing: spec.spacing,
        symmetry: spec
            .symmetry
            .as_ref()
            .map(|symmetry| symmetry.resolve(mesh))
            .transpose()
            .map_err(|message| (".symmetry".to_string(), message))?,
        samples,
    })
}

/// Layers by index or name (`field`, for messages), sorted and without repeats.
fn resolve_layers(refs: &[LayerRef], mesh: &Mesh, field: &str) -> Result<Vec<LayerId>, FieldError> {
    if refs.is_empty() {
        let message = "a stroke needs at least one active layer";
        return Err((field.into(), message.into()));
    }
    let mut layers = Vec::new();
    for (k, layer) in refs.iter().enumerate() {
        let id = match layer {
            LayerRef::Index(i) if (*i as usize) < mesh.layer_count() => Ok(*i),
            LayerRef::Index(i) => Err(format!(
                "layer {i} does not exist (the mesh has {} layers)",
                mesh.layer_count()
            )),
            LayerRef::Name(name) => mesh
                .layer_names()
                .iter()
                .position(|n| n == name)
                .map(|i| i as LayerId)
                .ok_or_else(|| {
                    format!(
                        "no layer is named `{}` (the mesh has: {})",
                        escape(name),
                        escape(&mesh.layer_names().join(", "))
                    )
                }),
        };
        layers.push(id.map_err(|message| (format!("{field}[{k}]"), message))?);
    }
    layers.sort_unstable();
    layers.dedup();
    Ok(layers)
}

/// The samples, each position usable, pressure in [0, 1] and normal a direction.
fn resolve_samples(specs: &[SampleSpec]) -> Result<Vec<Sample>, FieldError> {
    if specs.is_empty() {
        return Err((
            ".samples".into(),
            "a stroke needs at least one sample".into(),
        ));
    }
    if specs.len() > MAX_SAMPLES_PER_STROKE {
        let message = format!(
            "{} samples is more than a stroke may have ({MAX_SAMPLES_PER_STROKE})",
            specs.len()
        );
        return Err((".samples".into(), message));
    }
    let mut samples = Vec::with_capacity(specs.len());
    for (k, s) in specs.iter().enumerate() {
        let fail = |field: &str, message: String| Err((format!(".samples[{k}].{field}"), message));
        let position = Vec3::from_array(s.position);
        if !position.is_finite() || position.abs().max_element() > MAX_COORDINATE {
            return fail(
                "position",
                format!("{:?} is not a usable position", s.position),
            );
        }
        if !(0.0..=1.0).contains(&s.pressure) {
            return fail("pressure", format!("{} is outside [0, 1]", s.pressure));
        }
        let normal = match s.normal {
            None => None,
            Some(n) => match Vec3::from_array(n).try_normalize() {
                Some(unit) => Some(unit),
                None => return fail("normal", format!("{n:?} is not a direction")),
            },
        };
        samples.push(Sample {
            position,
            pressure: s.pressure,
            normal,
        });
    }
    Ok(samples)
}

/// The paint a stroke lays down: required by the paint brush (its strength scales the
/// opacity), refused by the mask brush.
fn resolve_stroke_paint(spec: &StrokeSpec) -> Result<Option<Paint>, FieldError> {
    let fail = |message: &str| Err((".paint".to_string(), message.to_string()));
    match (&spec.paint, spec.brush) {
        (Some(_), BrushKind::Mask) => {
            fail("the mask brush paints the mask, not a material: leave `paint` out")
        }
        (Some(paint), kind) => {
            let mut paint = resolve_paint(paint)
                .map_err(|(field, message)| (format!(".paint{field}"), message))?;
            if kind == BrushKind::Paint {
                paint.opacity *= spec.strength;
            }
            Ok(Some(paint))
        }
        (None, BrushKind::Paint) => {
            fail("the paint brush needs a `paint` (e.g. {\"material\": \"rust\"})")
        }
        (None, _) => Ok(None),
    }
}

fn preset(name: &str) -> Result<Brdf, String> {
    material::preset(name).map(|m| m.brdf).ok_or_else(|| {
        let names: Vec<&str> = material::PRESETS.iter().map(|m| m.name).collect();
        format!(
            "no material named `{}` (presets: {})",
            escape(name),
            names.join(", ")
        )
    })
}

/// A paint spec checked and turned into a [`Paint`]; errors name the field under `.paint`.
fn resolve_paint(spec: &PaintSpec) -> Result<Paint, (String, String)> {
    let fail = |field: &str, message: String| Err((field.to_string(), message));
    let unit = |field: &str, values: &[f32]| -> Result<(), (String, String)> {
        match values.iter().find(|v| !(0.0..=1.0).contains(*v)) {
            Some(v) => Err((field.to_string(), format!("{v} is outside [0, 1]"))),
            None => Ok(()),
        }
    };
    let mut brdf = match &spec.material {
        Some(name) => match preset(name) {
            Ok(brdf) => brdf,
            Err(message) => return fail(".material", message),
        },
        None => {
            let missing = [
                ("diffuse", spec.diffuse.is_none()),
                ("specular", spec.specular.is_none()),
                ("roughness", spec.roughness.is_none()),
            ];
            if let Some((field, _)) = missing.iter().find(|(_, absent)| *absent) {
                return fail(
                    &format!(".{field}"),
                    "missing: give a `material`, or all of `diffuse`, `specular` and `roughness`"
                        .into(),
                );
            }
            Brdf::CLAY
        }
    };
    if let Some(diffuse) = spec.diffuse {
        unit(".diffuse", &diffuse)?;
        brdf.diffuse = diffuse;
    }
    if let Some(specular) = spec.specular {
        unit(".specular", &specular)?;
        brdf.specular = specular;
    }
    if let Some(roughness) = spec.roughness {
        unit(".roughness", &[roughness])?;
        brdf.roughness = roughness;
    }
    let opacity = spec.opacity.unwrap_or(1.0);
    unit(".opacity", &[opacity])?;
    let stencil = match &spec.stencil {
        None => None,
        Some(stencil) => Some(Arc::new(
            resolve_stencil(stencil, brdf)
                .map_err(|(field, message)| (format!(".stencil{field}"), message))?,
        )),
    };
    Ok(Paint {
        brdf,
        stencil,
        opacity,
    })
}

fn resolve_stencil(spec: &StencilSpec, brdf: Brdf) -> Result<Stencil, (String, String)> {
    let fail = |field: &str, message: String| Err((field.to_string(), message));
    if !(spec.tile.is_finite() && spec.tile > 0.0) {
        return fail(".tile", format!("{} is not a positive length", spec.tile));
    }
    match (&spec.pattern, &spec.png) {
        (Some(name), None) => {
            let Some(pattern) = Pattern::from_name(name) else {
                let names: Vec<&str> = Pattern::ALL.iter().map(|p| p.name()).collect();
                return fail(
                    ".pattern",
                    format!(
                        "no pattern named `{}` (patterns: {})",
                        escape(name),
                        names.join(", ")
                    ),
                );
            };
            let second = match &spec.with {
                Some(name) => preset(name).map_err(|m| (".with".to_string(), m))?,
                None => Brdf::CLAY,
            };
            Ok(Stencil::pattern(pattern, brdf, second, spec.tile))
        }
        (None, Some(path)) => {
            if spec.with.is_some() {
                return fail(".with", "only patterns mix two materials".into());
            }
            let shown = escape(path);
            let bytes = crate::files::read_input(std::path::Path::new(path), MAX_STENCIL_BYTES)
                .map_err(|e| (".png".to_string(), format!("cannot read `{shown}`: {e}")))?;
            Stencil::from_png(&bytes, brdf.specular, spec.tile)
                .map_err(|e| (".png".to_string(), format!("`{shown}`: {e}")))
        }
        (Some(_), Some(_)) => fail("", "give either `pattern` or `png`, not both".into()),
        (None, None) => fail("", "give a `pattern` or a `png`".into()),
    }
}
