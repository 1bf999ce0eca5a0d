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
//!     "samples": [{"position": [0.5, 0.5, 0.01], "pressure": 1.0, "normal": [0, 0, 1]}]
//!   }]
//! }
//! ```
//!
//! `falloff`, `invert`, `spacing`, `pressure` and `normal` may be left out (blend n=3, false,
//! 0.25, 1, the surface normal under the brush). Every problem is reported with the stroke and
//! sample it is in.

use glam::Vec3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::{Brush, BrushKind, Falloff};
use crate::mesh::{LayerId, MAX_COORDINATE, Mesh};

/// A radius beyond this many times the mesh's bounding-box diagonal is rejected as absurd.
pub const MAX_RADIUS_OVER_EXTENT: f32 = 10.0;
/// A radius below this share of the mean edge length touches nothing and is rejected.
const MIN_RADIUS_OVER_EDGE: f32 = 0.05;
const MAX_SAMPLES: usize = 1_000_000;

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

fn default_spacing() -> f32 {
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
    #[serde(default = "default_spacing")]
    pub spacing: f32,
    pub samples: Vec<SampleSpec>,
}

/// A stroke file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrokeFile {
    #[serde(default = "version_one")]
    pub version: u32,
    pub strokes: Vec<StrokeSpec>,
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
    /// Active layers, sorted.
    pub layers: Vec<LayerId>,
    /// Resampling step as a share of the radius.
    pub spacing: f32,
    pub samples: Vec<Sample>,
}

impl StrokeFile {
    /// Parses JSON; `source_name` names the file in messages.
    pub fn parse(text: &str, source_name: &str) -> Result<StrokeFile, StrokeError> {
        let file: StrokeFile = serde_json::from_str(text).map_err(|e| StrokeError::Json {
            source_name: source_name.to_string(),
            line: e.line(),
            column: e.column(),
            message: e
                .to_string()
                .split(" at line ")
                .next()
                .unwrap_or_default()
                .to_string(),
        })?;
        if file.version != 1 {
            return Err(StrokeError::Invalid {
                source_name: source_name.to_string(),
                location: "version".into(),
                message: format!("version {} is not supported (expected 1)", file.version),
            });
        }
        Ok(file)
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Checks every stroke against `mesh` and resolves layer names.
    pub fn resolve(&self, mesh: &Mesh, source_name: &str) -> Result<Vec<Stroke>, StrokeError> {
        let extent = mesh
            .bounds()
            .map(|(lo, hi)| (hi - lo).length())
            .unwrap_or(0.0)
            .max(f32::MIN_POSITIVE);
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

fn resolve_stroke(
    spec: &StrokeSpec,
    mesh: &Mesh,
    extent: f32,
    edge: f32,
) -> Result<Stroke, (String, String)> {
    let fail = |field: &str, message: String| Err((field.to_string(), message));
    if !(spec.radius.is_finite() && spec.radius > 0.0) {
        return fail(
            ".radius",
            format!("{} is not a positive length", spec.radius),
        );
    }
    if spec.radius > MAX_RADIUS_OVER_EXTENT * extent {
        return fail(
            ".radius",
            format!(
                "{} is more than {MAX_RADIUS_OVER_EXTENT} times the mesh's size ({extent})",
                spec.radius
            ),
        );
    }
    if spec.radius < MIN_RADIUS_OVER_EDGE * edge {
        return fail(
            ".radius",
            format!(
                "{} is far below the mean edge length {edge}: it would touch nothing",
                spec.radius
            ),
        );
    }
    if !(0.0..=1.0).contains(&spec.strength) {
        return fail(".strength", format!("{} is outside [0, 1]", spec.strength));
    }
    if !(0.01..=2.0).contains(&spec.spacing) {
        return fail(
            ".spacing",
            format!(
                "{} is outside [0.01, 2] (a share of the radius)",
                spec.spacing
            ),
        );
    }
    if let Falloff::Blend { n } = spec.falloff
        && !(3..=16).contains(&n)
    {
        return fail(
            ".falloff.n",
            format!("{n} is outside 3..=16 (the blend needs n > 2)"),
        );
    }
    if spec.samples.is_empty() {
        return fail(".samples", "a stroke needs at least one sample".into());
    }
    if spec.samples.len() > MAX_SAMPLES {
        return fail(
            ".samples",
            format!("{} samples is more than {MAX_SAMPLES}", spec.samples.len()),
        );
    }
    if spec.layers.is_empty() {
        return fail(".layers", "a stroke needs at least one active layer".into());
    }
    let mut layers = Vec::new();
    for (k, layer) in spec.layers.iter().enumerate() {
        let id = match layer {
            LayerRef::Index(i) if (*i as usize) < mesh.layer_count() => *i,
            LayerRef::Index(i) => {
                return fail(
                    &format!(".layers[{k}]"),
                    format!(
                        "layer {i} does not exist (the mesh has {} layers)",
                        mesh.layer_count()
                    ),
                );
            }
            LayerRef::Name(name) => match mesh.layer_names().iter().position(|n| n == name) {
                Some(i) => i as LayerId,
                None => {
                    return fail(
                        &format!(".layers[{k}]"),
                        format!(
                            "no layer is named `{name}` (the mesh has: {})",
                            mesh.layer_names().join(", ")
                        ),
                    );
                }
            },
        };
        layers.push(id);
    }
    layers.sort_unstable();
    layers.dedup();
    let mut samples = Vec::with_capacity(spec.samples.len());
    for (k, s) in spec.samples.iter().enumerate() {
        let at = |field: &str| format!(".samples[{k}].{field}");
        let position = Vec3::from_array(s.position);
        if !position.is_finite() || position.abs().max_element() > MAX_COORDINATE {
            return fail(
                &at("position"),
                format!("{:?} is not a usable position", s.position),
            );
        }
        if !(0.0..=1.0).contains(&s.pressure) {
            return fail(&at("pressure"), format!("{} is outside [0, 1]", s.pressure));
        }
        let normal = match s.normal {
            None => None,
            Some(n) => match Vec3::from_array(n).try_normalize() {
                Some(unit) => Some(unit),
                None => return fail(&at("normal"), format!("{n:?} is not a direction")),
            },
        };
        samples.push(Sample {
            position,
            pressure: s.pressure,
            normal,
        });
    }
    Ok(Stroke {
        brush: Brush {
            kind: spec.brush,
            radius: spec.radius,
            strength: spec.strength,
            falloff: spec.falloff,
            invert: spec.invert,
        },
        layers,
        spacing: spec.spacing,
        samples,
    })
}

/// Resamples a polyline of samples every `step` of arc length, interpolating pressure and
/// normal; the first and last samples are kept.
pub fn resample(samples: &[Sample], step: f32) -> Vec<Sample> {
    let Some(first) = samples.first() else {
        return Vec::new();
    };
    if samples.len() == 1 || step.is_nan() || step <= 0.0 {
        return samples.to_vec();
    }
    let mut out = vec![*first];
    let mut carried = 0.0f32; // arc length since the last emitted sample
    for pair in samples.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let length = a.position.distance(b.position);
        let mut at = step - carried; // distance along this segment of the next emission
        while at <= length && length > 0.0 {
            let t = at / length;
            out.push(Sample {
                position: a.position.lerp(b.position, t),
                pressure: a.pressure + (b.pressure - a.pressure) * t,
                normal: match (a.normal, b.normal) {
                    (Some(na), Some(nb)) => na.lerp(nb, t).try_normalize().or(Some(na)),
                    (n, None) | (None, n) => n,
                },
            });
            at += step;
        }
        carried = length - (at - step);
    }
    let last = *samples.last().unwrap_or(first);
    if out
        .last()
        .is_some_and(|s| s.position.distance(last.position) > 1e-3 * step)
    {
        out.push(last);
    }
    out
}
