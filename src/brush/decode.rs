//! The stroke file's JSON turned into [`StrokeFile`] by hand, so that every mistake is told in
//! our words with the field it is in (`strokes[2].layers[0]: …`) and what the field allows,
//! rather than in a parser's (`untagged enum LayerRef`, `expected value`). Counts are bounded
//! here, before anything is built from them.

use serde_json::{Map, Value};

use super::stroke::{
    LayerRef, PaintSpec, SampleSpec, StencilSpec, StrokeFile, StrokeSpec, default_spacing,
};
use super::{BrushKind, Falloff, SymmetrySpec};
use crate::files::escape;

/// The most strokes a stroke file may hold.
pub const MAX_STROKES: usize = 100_000;
/// The most samples one stroke of a file may have.
pub const MAX_SAMPLES_PER_STROKE: usize = 1_000_000;
/// The most samples a stroke file may hold, all strokes together.
pub const MAX_SAMPLES_PER_FILE: usize = 10_000_000;

/// A mistake: where (`strokes[0].radius`, empty for the whole file) and what.
pub(super) type Mistake = (String, String);

const FILE_FIELDS: &[&str] = &["version", "strokes", "fuse"];
const STROKE_FIELDS: &[&str] = &[
    "brush", "radius", "strength", "falloff", "invert", "layers", "paint", "spacing", "symmetry",
    "samples",
];
const SAMPLE_FIELDS: &[&str] = &["position", "pressure", "normal"];
const PAINT_FIELDS: &[&str] = &[
    "material",
    "diffuse",
    "specular",
    "roughness",
    "opacity",
    "stencil",
];
const STENCIL_FIELDS: &[&str] = &["pattern", "png", "with", "tile"];
const CURVES: &[&str] = &["blend", "smooth", "sphere", "linear"];

/// A JSON object being read, and where it is in the file.
struct Object<'a> {
    map: &'a Map<String, Value>,
    at: String,
}

impl<'a> Object<'a> {
    /// `value` as an object whose keys are all among `allowed`.
    fn new(value: &'a Value, at: &str, allowed: &[&str]) -> Result<Object<'a>, Mistake> {
        let Value::Object(map) = value else {
            return Err((
                at.to_string(),
                format!("{} where an object {{…}} belongs", describe(value)),
            ));
        };
        if let Some(key) = map.keys().find(|k| !allowed.contains(&k.as_str())) {
            return Err((
                at.to_string(),
                format!(
                    "unknown field `{}` (the fields are: {})",
                    escape(key),
                    allowed.join(", ")
                ),
            ));
        }
        Ok(Object {
            map,
            at: at.to_string(),
        })
    }

    /// Where `key` is.
    fn at(&self, key: &str) -> String {
        if self.at.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.at)
        }
    }

    fn get(&self, key: &str) -> Option<&'a Value> {
        self.map.get(key)
    }

    /// A field that must be there.
    fn required(&self, key: &str, what: &str) -> Result<&'a Value, Mistake> {
        self.get(key)
            .ok_or_else(|| (self.at(key), format!("missing (give {what})")))
    }

    fn number(&self, key: &str) -> Result<Option<f32>, Mistake> {
        self.get(key).map(|v| number(v, &self.at(key))).transpose()
    }

    fn required_number(&self, key: &str, what: &str) -> Result<f32, Mistake> {
        number(self.required(key, what)?, &self.at(key))
    }

    fn string(&self, key: &str, what: &str) -> Result<Option<String>, Mistake> {
        self.get(key)
            .map(|v| string(v, &self.at(key), what))
            .transpose()
    }

    fn triple(&self, key: &str, what: &str) -> Result<Option<[f32; 3]>, Mistake> {
        self.get(key)
            .map(|v| triple(v, &self.at(key), what))
            .transpose()
    }
}

/// A value in words, for messages: its kind and, when short, itself.
fn describe(value: &Value) -> String {
    match value {
        Value::Null => "null".into(),
        Value::Bool(b) => format!("`{b}`"),
        Value::Number(n) => format!("the number {n}"),
        Value::String(s) if s.chars().count() <= 40 => format!("the text \"{}\"", escape(s)),
        Value::String(_) => "a long text".into(),
        Value::Array(_) => "a list [...]".into(),
        Value::Object(_) => "an object {…}".into(),
    }
}

fn number(value: &Value, at: &str) -> Result<f32, Mistake> {
    value.as_f64().map(|n| n as f32).ok_or_else(|| {
        (
            at.to_string(),
            format!("{} is not a number", describe(value)),
        )
    })
}

fn string(value: &Value, at: &str, what: &str) -> Result<String, Mistake> {
    value
        .as_str()
        .map(str::to_string)
        .ok_or_else(|| (at.to_string(), format!("{} is not {what}", describe(value))))
}

fn list<'a>(value: &'a Value, at: &str, what: &str) -> Result<&'a Vec<Value>, Mistake> {
    value.as_array().ok_or_else(|| {
        (
            at.to_string(),
            format!("{} is not a list of {what}", describe(value)),
        )
    })
}

/// Three numbers, `[x, y, z]`.
fn triple(value: &Value, at: &str, what: &str) -> Result<[f32; 3], Mistake> {
    let wrong = || (at.to_string(), format!("{} is not {what}", describe(value)));
    let items = value.as_array().ok_or_else(wrong)?;
    if items.len() != 3 {
        return Err((
            at.to_string(),
            format!("{} numbers where 3 belong ({what})", items.len()),
        ));
    }
    let mut out = [0.0; 3];
    for (k, item) in items.iter().enumerate() {
        out[k] = number(item, &format!("{at}[{k}]"))?;
    }
    Ok(out)
}

/// A whole stroke file.
pub(super) fn file(value: &Value) -> Result<StrokeFile, Mistake> {
    let object = Object::new(value, "", FILE_FIELDS)?;
    let version = match object.get("version") {
        None => 1,
        Some(v) => v
            .as_u64()
            .filter(|&n| n <= u32::MAX as u64)
            .ok_or_else(|| {
                (
                    "version".to_string(),
                    format!("{} is not a version number (1)", describe(v)),
                )
            })? as u32,
    };
    let items = list(
        object.required("strokes", "a list of strokes")?,
        "strokes",
        "strokes",
    )?;
    if items.len() > MAX_STROKES {
        return Err((
            "strokes".into(),
            format!(
                "{} strokes is more than a stroke file may hold ({MAX_STROKES}); split the file",
                items.len()
            ),
        ));
    }
    let mut samples = 0usize;
    let mut strokes = Vec::with_capacity(items.len());
    for (i, item) in items.iter().enumerate() {
        let stroke = stroke(item, &format!("strokes[{i}]"))?;
        samples += stroke.samples.len();
        if samples > MAX_SAMPLES_PER_FILE {
            return Err((
                format!("strokes[{i}].samples"),
                format!(
                    "the file holds more than {MAX_SAMPLES_PER_FILE} samples, the most a stroke \
                     file may hold; split the file"
                ),
            ));
        }
        strokes.push(stroke);
    }
    let fuse = match object.get("fuse") {
        None => Vec::new(),
        Some(value) => layers(value, "fuse")?,
    };
    Ok(StrokeFile {
        version,
        strokes,
        fuse,
    })
}

fn stroke(value: &Value, at: &str) -> Result<StrokeSpec, Mistake> {
    let object = Object::new(value, at, STROKE_FIELDS)?;
    let invert = match object.get("invert") {
        None => false,
        Some(v) => v.as_bool().ok_or_else(|| {
            (
                object.at("invert"),
                format!("{} is not `true` or `false`", describe(v)),
            )
        })?,
    };
    Ok(StrokeSpec {
        brush: brush(
            object.required("brush", "a brush name")?,
            &object.at("brush"),
        )?,
        radius: object.required_number("radius", "a length in world units")?,
        strength: object.required_number("strength", "a number from 0 to 1")?,
        falloff: match object.get("falloff") {
            None => Falloff::default(),
            Some(v) => falloff(v, &object.at("falloff"))?,
        },
        invert,
        layers: layers(
            object.required("layers", "a list of layer indices or names")?,
            &object.at("layers"),
        )?,
        paint: object
            .get("paint")
            .map(|v| paint(v, &object.at("paint")))
            .transpose()?,
        spacing: object.number("spacing")?.unwrap_or_else(default_spacing),
        symmetry: object
            .get("symmetry")
            .map(|v| symmetry(v, &object.at("symmetry")))
            .transpose()?,
        samples: samples(
            object.required("samples", "a list of samples")?,
            &object.at("samples"),
        )?,
    })
}

fn symmetry(value: &Value, at: &str) -> Result<SymmetrySpec, Mistake> {
    if let Some(axis) = value.as_str() {
        return Ok(SymmetrySpec::Axis(axis.to_string()));
    }
    let object = Object::new(value, at, &["point", "normal"])
        .map_err(|_| (at.to_string(), format!("{} is not an axis (\"x\", \"y\", \"z\") or a plane {{\"point\": [..], \"normal\": [..]}}", describe(value))))?;
    Ok(SymmetrySpec::Plane {
        point: object
            .triple("point", "a point [x, y, z]")?
            .ok_or_else(|| {
                (
                    object.at("point"),
                    "is missing: a point [x, y, z]".to_string(),
                )
            })?,
        normal: object
            .triple("normal", "a direction [x, y, z]")?
            .ok_or_else(|| {
                (
                    object.at("normal"),
                    "is missing: a direction [x, y, z]".to_string(),
                )
            })?,
    })
}

fn brush(value: &Value, at: &str) -> Result<BrushKind, Mistake> {
    let names: Vec<&str> = BrushKind::ALL.iter().map(|b| b.name()).collect();
    let unknown = || {
        (
            at.to_string(),
            format!(
                "{} is not a brush (brushes: {}, or move for grab)",
                describe(value),
                names.join(", ")
            ),
        )
    };
    match value.as_str() {
        Some("move") => Ok(BrushKind::Grab),
        Some(name) => BrushKind::ALL
            .into_iter()
            .find(|b| b.name() == name)
            .ok_or_else(unknown),
        None => Err(unknown()),
    }
}

fn falloff(value: &Value, at: &str) -> Result<Falloff, Mistake> {
    let object = Object::new(value, at, &["curve", "n", "inner"])?;
    let curve = object.string("curve", "a curve name")?.ok_or_else(|| {
        (
            object.at("curve"),
            format!("missing (give one of {})", CURVES.join(", ")),
        )
    })?;
    let n = object.get("n");
    for key in ["n", "inner"] {
        if object.get(key).is_some() && curve != "blend" {
            return Err((
                object.at(key),
                format!("only the blend curve takes an `{key}`"),
            ));
        }
    }
    match curve.as_str() {
        "blend" => {
            let n = match n {
                None => 3,
                Some(v) => v
                    .as_u64()
                    .filter(|&n| n <= u32::MAX as u64)
                    .ok_or_else(|| {
                        (
                            object.at("n"),
                            format!("{} is not a whole number (3 to 16)", describe(v)),
                        )
                    })? as u32,
            };
            let inner = object.number("inner")?.unwrap_or(0.0);
            Ok(Falloff::Blend { n, inner })
        }
        "smooth" => Ok(Falloff::Smooth),
        "sphere" => Ok(Falloff::Sphere),
        "linear" => Ok(Falloff::Linear),
        other => Err((
            object.at("curve"),
            format!(
                "no curve is named `{}` (curves: {})",
                escape(other),
                CURVES.join(", ")
            ),
        )),
    }
}

fn layers(value: &Value, at: &str) -> Result<Vec<LayerRef>, Mistake> {
    let items = list(value, at, "layer indices or names")?;
    items
        .iter()
        .enumerate()
        .map(|(k, item)| match item {
            Value::String(name) => Ok(LayerRef::Name(name.clone())),
            Value::Number(n) => match n.as_u64().filter(|&i| i <= u32::MAX as u64) {
                Some(i) => Ok(LayerRef::Index(i as u32)),
                None => Err((
                    format!("{at}[{k}]"),
                    format!("{n} is not a layer index (0, 1, 2, …)"),
                )),
            },
            other => Err((
                format!("{at}[{k}]"),
                format!(
                    "{} is not a layer (give its index, 0, 1, …, or its name)",
                    describe(other)
                ),
            )),
        })
        .collect()
}

fn samples(value: &Value, at: &str) -> Result<Vec<SampleSpec>, Mistake> {
    let items = list(value, at, "samples")?;
    if items.len() > MAX_SAMPLES_PER_STROKE {
        return Err((
            at.to_string(),
            format!(
                "{} samples is more than a stroke may have ({MAX_SAMPLES_PER_STROKE}); split the stroke",
                items.len()
            ),
        ));
    }
    items
        .iter()
        .enumerate()
        .map(|(k, item)| {
            let object = Object::new(item, &format!("{at}[{k}]"), SAMPLE_FIELDS)?;
            let position = object.required("position", "[x, y, z]")?;
            Ok(SampleSpec {
                position: triple(position, &object.at("position"), "a position [x, y, z]")?,
                pressure: object.number("pressure")?.unwrap_or(1.0),
                normal: object.triple("normal", "a direction [x, y, z]")?,
            })
        })
        .collect()
}

fn paint(value: &Value, at: &str) -> Result<PaintSpec, Mistake> {
    let object = Object::new(value, at, PAINT_FIELDS)?;
    Ok(PaintSpec {
        material: object.string("material", "a material name")?,
        diffuse: object.triple("diffuse", "a colour [r, g, b]")?,
        specular: object.triple("specular", "a colour [r, g, b]")?,
        roughness: object.number("roughness")?,
        opacity: object.number("opacity")?,
        stencil: object
            .get("stencil")
            .map(|v| stencil(v, &object.at("stencil")))
            .transpose()?,
    })
}

fn stencil(value: &Value, at: &str) -> Result<StencilSpec, Mistake> {
    let object = Object::new(value, at, STENCIL_FIELDS)?;
    Ok(StencilSpec {
        pattern: object.string("pattern", "a pattern name")?,
        png: object.string("png", "a file path")?,
        with: object.string("with", "a material name")?,
        tile: object.required_number("tile", "the world size of one repeat")?,
    })
}
