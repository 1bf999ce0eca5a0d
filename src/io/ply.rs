//! Stanford PLY, ASCII and binary. Written as binary little-endian with the full vertex state
//! (position, normal, BRDF, layer, mask flag) and a face layer; layer names travel in comments.
//! The reader takes any property order and scalar type, skips elements and properties it does
//! not know, triangulates polygons as fans, and never trusts a count in the header to size an
//! allocation.

use std::io::{self, Write};

use glam::Vec3;

use super::import::{ImportReport, Parsed};
use super::{IoError, WRITE_CHUNK, flush_chunk};
use crate::material::{linear_to_srgb, srgb_to_linear};
use crate::mesh::{Brdf, INVALID, LayerId, Mesh, Soup, VertexFlags};

/// Layer ids above this are treated as corrupt (a layer is a user-facing label, not an index
/// space).
const MAX_LAYERS: u32 = 65_536;

const BRDF_PROPERTIES: [&str; 7] = [
    "diffuse_r",
    "diffuse_g",
    "diffuse_b",
    "specular_r",
    "specular_g",
    "specular_b",
    "roughness",
];

#[derive(Debug, Clone, Copy, PartialEq)]
enum Encoding {
    Ascii,
    Binary { little_endian: bool },
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(word: &str) -> Option<Scalar> {
        Some(match word {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Debug, Clone)]
struct Property {
    name: String,
    value: Scalar,
    /// `Some(count type)` for list properties.
    list: Option<Scalar>,
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

struct Header {
    encoding: Encoding,
    /// Written by slayer (`comment written by slayer`): only then are properties with common
    /// names (`flags`, `layer`) read as ours. Another tool's `flags` is not our mask.
    ours: bool,
    elements: Vec<Element>,
    layer_names: Vec<(u32, String)>,
    /// Layers marked `comment slayer fuse ID`: their proximity policy is fuse.
    fuse_layers: Vec<u32>,
    /// Byte offset of the body.
    body: usize,
    /// Lines in the header, for ASCII line numbers.
    lines: usize,
}

fn parse_header(bytes: &[u8], name: &str) -> Result<Header, IoError> {
    let fail = |line: usize, message: &str| Err(IoError::parse(name, Some(line), message));
    let mut lines = HeaderLines::default();
    let mut offset = 0;
    let mut line_number = 0;
    loop {
        let Some(end) = bytes[offset..].iter().position(|&b| b == b'\n') else {
            return fail(line_number + 1, "header ends before `end_header`");
        };
        line_number += 1;
        let raw = &bytes[offset..offset + end];
        offset += end + 1;
        let Ok(line) = std::str::from_utf8(raw) else {
            return fail(line_number, "header is not text");
        };
        let words: Vec<&str> = line.split_whitespace().collect();
        if line_number == 1 {
            if words != ["ply"] {
                return fail(1, "not a PLY file (first line must be `ply`)");
            }
            continue;
        }
        match lines.take(&words) {
            Ok(true) => break,
            Ok(false) => {}
            Err(HeaderLineError::Unexpected) => {
                return fail(
                    line_number,
                    &format!("unexpected header line `{}`", line.trim()),
                );
            }
            Err(HeaderLineError::Bad(message)) => return fail(line_number, message),
        }
    }
    let Some(encoding) = lines.encoding else {
        return fail(line_number, "header has no `format` line");
    };
    Ok(Header {
        encoding,
        ours: lines.ours,
        elements: lines.elements,
        layer_names: lines.layer_names,
        fuse_layers: lines.fuse_layers,
        body: offset,
        lines: line_number,
    })
}

/// What the header's lines after the first have said so far.
#[derive(Default)]
struct HeaderLines {
    encoding: Option<Encoding>,
    ours: bool,
    elements: Vec<Element>,
    layer_names: Vec<(u32, String)>,
    fuse_layers: Vec<u32>,
}

/// Why a header line was refused.
enum HeaderLineError {
    /// A line of no known shape (its text goes in the message).
    Unexpected,
    Bad(&'static str),
}

impl HeaderLines {
    /// Takes one line's words; `true` at `end_header`.
    fn take(&mut self, words: &[&str]) -> Result<bool, HeaderLineError> {
        use HeaderLineError::Bad;
        match words {
            ["format", kind, _version] => {
                self.encoding = Some(match *kind {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Binary {
                        little_endian: true,
                    },
                    "binary_big_endian" => Encoding::Binary {
                        little_endian: false,
                    },
                    _ => return Err(Bad("unknown PLY format")),
                })
            }
            ["comment", "written", "by", "slayer"] => self.ours = true,
            ["comment", "slayer", "fuse", id] => {
                if let Ok(id) = id.parse::<u32>() {
                    self.fuse_layers.push(id);
                }
            }
            ["comment", "slayer", "layer", id, rest @ ..] => {
                if let Ok(id) = id.parse::<u32>() {
                    self.layer_names.push((id, rest.join(" ")));
                }
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", element, count] => {
                let Ok(count) = count.parse::<usize>() else {
                    return Err(Bad("element count is not a non-negative integer"));
                };
                self.elements.push(Element {
                    name: element.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", "list", count_type, value_type, property] => {
                let (Some(count), Some(value)) =
                    (Scalar::parse(count_type), Scalar::parse(value_type))
                else {
                    return Err(Bad("unknown property type"));
                };
                if !count.is_integer() {
                    return Err(Bad("list count type must be an integer type"));
                }
                self.push_property(property, value, Some(count))?;
            }
            ["property", value_type, property] => {
                let Some(value) = Scalar::parse(value_type) else {
                    return Err(Bad("unknown property type"));
                };
                self.push_property(property, value, None)?;
            }
            ["end_header"] => return Ok(true),
            _ => return Err(HeaderLineError::Unexpected),
        }
        Ok(false)
    }

    fn push_property(
        &mut self,
        name: &str,
        value: Scalar,
        list: Option<Scalar>,
    ) -> Result<(), HeaderLineError> {
        let Some(element) = self.elements.last_mut() else {
            return Err(HeaderLineError::Bad("property before any element"));
        };
        element.properties.push(Property {
            name: name.to_string(),
            value,
            list,
        });
        Ok(())
    }
}

/// Reads values from the body in either encoding.
struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    encoding: Encoding,
    /// ASCII: the current line's words.
    words: Vec<&'a str>,
    word: usize,
    line: usize,
    name: &'a str,
}

impl<'a> Body<'a> {
    fn error(&self, message: impl Into<String>) -> IoError {
        let line = match self.encoding {
            Encoding::Ascii => Some(self.line),
            Encoding::Binary { .. } => None,
        };
        IoError::parse(self.name, line, message)
    }

    /// ASCII rows are lines; a new element row starts on a new line.
    fn start_row(&mut self) -> Result<(), IoError> {
        if self.encoding != Encoding::Ascii {
            return Ok(());
        }
        loop {
            if self.at >= self.bytes.len() {
                return Err(self.error("file ends before all elements are read"));
            }
            let end = self.bytes[self.at..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(self.bytes.len(), |e| self.at + e);
            let raw = &self.bytes[self.at..end];
            self.at = end + 1;
            self.line += 1;
            let text = std::str::from_utf8(raw).map_err(|_| self.error("body line is not text"))?;
            self.words = text.split_whitespace().collect();
            self.word = 0;
            if !self.words.is_empty() {
                return Ok(());
            }
        }
    }

    fn read(&mut self, scalar: Scalar) -> Result<f64, IoError> {
        match self.encoding {
            Encoding::Ascii => {
                let Some(word) = self.words.get(self.word) else {
                    return Err(self.error("row has too few values"));
                };
                self.word += 1;
                let value = if scalar.is_integer() {
                    word.parse::<i64>().map(|v| v as f64).ok()
                } else {
                    word.parse::<f64>().ok()
                };
                value.ok_or_else(|| self.error(format!("`{word}` is not a valid {scalar:?}")))
            }
            Encoding::Binary { little_endian } => {
                let size = scalar.size();
                let Some(raw) = self.bytes.get(self.at..self.at + size) else {
                    return Err(self.error("file ends before all elements are read"));
                };
                self.at += size;
                let mut buf = [0u8; 8];
                buf[..size].copy_from_slice(raw);
                if !little_endian {
                    buf[..size].reverse();
                }
                Ok(match scalar {
                    Scalar::I8 => buf[0] as i8 as f64,
                    Scalar::U8 => buf[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([buf[0], buf[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([buf[0], buf[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(buf),
                })
            }
        }
    }

    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.at)
    }
}

/// An index-like value: a non-negative integer that fits in `u32`.
fn as_index(value: f64) -> Option<u32> {
    (value >= 0.0 && value < INVALID as f64 && value.fract() == 0.0).then_some(value as u32)
}

/// Parses PLY bytes (`name` is used in messages).
pub(crate) fn parse_ply(bytes: &[u8], name: &str) -> Result<Parsed, IoError> {
    let header = parse_header(bytes, name)?;
    let mut body = Body {
        bytes,
        at: header.body,
        encoding: header.encoding,
        words: Vec::new(),
        word: 0,
        line: header.lines,
        name,
    };
    check_counts(&header, body.remaining(), name)?;
    let mut rows = Rows {
        ours: header.ours,
        ..Rows::default()
    };
    for element in &header.elements {
        rows.read_element(element, &mut body)?;
    }
    let mut report = ImportReport {
        not_kept: not_kept(&header),
        fuse_layers: header.fuse_layers.clone(),
        ..ImportReport::default()
    };
    report.non_finite_vertices = rows.positions.iter().filter(|p| !p.is_finite()).count();
    let layer_names = layer_names(&header.layer_names, &rows.face_layers);
    let brdfs = match (rows.has_brdf, rows.has_colour) {
        (true, _) => Some(rows.brdfs),
        (false, true) => Some(
            rows.colours
                .iter()
                .map(|&diffuse| Brdf {
                    diffuse,
                    ..Brdf::CLAY
                })
                .collect(),
        ),
        (false, false) => None,
    };
    Ok(Parsed {
        soup: Soup {
            positions: rows.positions,
            faces: rows.faces,
            face_layers: rows.face_layers,
        },
        layer_names,
        brdfs,
        flags: rows.ours.then_some(rows.masks),
        report,
        unreferenced: 0,
    })
}

/// Refuses a header whose element counts the file cannot hold, before anything is allocated
/// or read: every row takes at least one byte per property in binary, two in ASCII (a digit
/// and a separator).
fn check_counts(header: &Header, remaining: usize, name: &str) -> Result<(), IoError> {
    let mut needed: u128 = 0;
    for element in &header.elements {
        let row: usize = element
            .properties
            .iter()
            .map(|p| match (header.encoding, p.list) {
                (Encoding::Ascii, _) => 2,
                (Encoding::Binary { .. }, Some(count)) => count.size(),
                (Encoding::Binary { .. }, None) => p.value.size(),
            })
            .sum();
        needed += element.count as u128 * row as u128;
    }
    if needed > remaining as u128 {
        return Err(IoError::parse(
            name,
            None,
            format!(
                "the header's element counts need at least {needed} bytes, but the file holds {remaining} after its header"
            ),
        ));
    }
    Ok(())
}

/// The vertex properties slayer reads under any name, and those it reads only from its own
/// files.
const VERTEX_PROPERTIES: [&str; 6] = ["x", "y", "z", "red", "green", "blue"];
const OWN_VERTEX_PROPERTIES: [&str; 2] = ["flags", "layer"];

/// What the file holds that the mesh does not keep: normals, other vertex and face properties,
/// other elements.
fn not_kept(header: &Header) -> Vec<String> {
    let mut items = Vec::new();
    for element in &header.elements {
        let kept = |p: &Property| match element.name.as_str() {
            "vertex" => {
                VERTEX_PROPERTIES.contains(&p.name.as_str())
                    || BRDF_PROPERTIES.contains(&p.name.as_str())
                    || (header.ours && OWN_VERTEX_PROPERTIES.contains(&p.name.as_str()))
                    || (header.ours && ["nx", "ny", "nz"].contains(&p.name.as_str()))
            }
            "face" => is_index_list(p) || (header.ours && p.name == "layer"),
            _ => false,
        };
        if !matches!(element.name.as_str(), "vertex" | "face") {
            items.push(format!(
                "{} `{}` rows",
                element.count,
                crate::files::escape(&element.name)
            ));
            continue;
        }
        let dropped: Vec<String> = element
            .properties
            .iter()
            .filter(|p| !kept(p))
            .map(|p| format!("`{}`", crate::files::escape(&p.name)))
            .collect();
        if !dropped.is_empty() {
            items.push(format!("{} properties {}", element.name, dropped.join(" ")));
        }
    }
    items
}

/// What the body's vertex and face rows gave.
#[derive(Default)]
struct Rows {
    /// The file is slayer's: its `flags` and `layer` properties are ours.
    ours: bool,
    positions: Vec<Vec3>,
    brdfs: Vec<Brdf>,
    /// Linear diffuse albedo from `red`/`green`/`blue`.
    colours: Vec<[f32; 3]>,
    masks: Vec<VertexFlags>,
    /// The vertex element has every BRDF property.
    has_brdf: bool,
    /// The vertex element has `red`, `green` and `blue`.
    has_colour: bool,
    faces: Vec<[u32; 3]>,
    face_layers: Vec<LayerId>,
    saw_vertices: bool,
}

/// One row of an element, the properties slayer reads.
#[derive(Default)]
struct Row {
    position: [f32; 3],
    brdf: [f32; 7],
    colour: [f32; 3],
    flags: u32,
    polygon: Vec<u32>,
    layer: u32,
}

fn is_index_list(property: &Property) -> bool {
    property.list.is_some()
        && (property.name == "vertex_indices" || property.name == "vertex_index")
}

impl Rows {
    /// Reads every row of `element`: vertices and faces kept, other elements skipped.
    fn read_element(&mut self, element: &Element, body: &mut Body<'_>) -> Result<(), IoError> {
        let is_vertex = element.name == "vertex";
        let is_face = element.name == "face";
        if is_vertex {
            self.start_vertices(element, body)?;
        }
        if is_face && !element.properties.iter().any(is_index_list) {
            return Err(body.error("face element has no `vertex_indices` list"));
        }
        for row in 0..element.count {
            body.start_row()?;
            let read = read_row(element, (row, self.ours), body)?;
            if is_vertex {
                self.positions.push(Vec3::from_array(read.position));
                self.brdfs.push(Brdf::from_array(read.brdf));
                self.colours.push(read.colour);
                let mask = VertexFlags::from_bits_truncate(read.flags) & VertexFlags::PERSISTENT;
                self.masks.push(mask);
            } else if is_face {
                self.push_polygon(&read, row, body)?;
            }
        }
        Ok(())
    }

    /// Checks the one vertex element's properties.
    fn start_vertices(&mut self, element: &Element, body: &Body<'_>) -> Result<(), IoError> {
        if self.saw_vertices {
            return Err(body.error("more than one vertex element"));
        }
        self.saw_vertices = true;
        let has = |name: &str| {
            element
                .properties
                .iter()
                .any(|p| p.name == name && p.list.is_none())
        };
        if let Some(axis) = ["x", "y", "z"].into_iter().find(|a| !has(a)) {
            return Err(body.error(format!("vertex element has no `{axis}` property")));
        }
        self.has_brdf = BRDF_PROPERTIES.iter().all(|b| has(b));
        self.has_colour = ["red", "green", "blue"].iter().all(|c| has(c));
        Ok(())
    }

    /// A face row's polygon, checked and split into a fan of triangles.
    fn push_polygon(&mut self, read: &Row, row: usize, body: &Body<'_>) -> Result<(), IoError> {
        let polygon = &read.polygon;
        if polygon.len() < 3 {
            return Err(body.error(format!(
                "face {row} has {} corners; at least 3 are needed",
                polygon.len()
            )));
        }
        if let Some(&bad) = polygon
            .iter()
            .find(|&&i| i as usize >= self.positions.len())
        {
            return Err(body.error(format!(
                "face {row}: vertex index {bad} is out of range ({} vertices)",
                self.positions.len()
            )));
        }
        for k in 1..polygon.len() - 1 {
            self.faces.push([polygon[0], polygon[k], polygon[k + 1]]);
            self.face_layers.push(read.layer);
        }
        Ok(())
    }
}

/// Reads one row of `element` (its `row`th; `ours`: the file is slayer's), keeping what slayer
/// uses of it.
fn read_row(
    element: &Element,
    (row, ours): (usize, bool),
    body: &mut Body<'_>,
) -> Result<Row, IoError> {
    let is_vertex = element.name == "vertex";
    let is_face = element.name == "face";
    let mut read = Row::default();
    for property in &element.properties {
        if let Some(count_type) = property.list {
            let wanted = is_face && is_index_list(property);
            read_list(property, count_type, (row, wanted), body, &mut read)?;
            continue;
        }
        let value = body.read(property.value)?;
        if is_vertex {
            read_vertex_property(property, value, ours, &mut read);
        } else if is_face && ours && property.name == "layer" {
            read.layer = match as_index(value) {
                Some(l) if l < MAX_LAYERS => l,
                _ => {
                    return Err(
                        body.error(format!("face {row}: layer {value} is not a valid layer id"))
                    );
                }
            };
        }
    }
    Ok(read)
}

/// A list property: read through, and kept as the polygon when `wanted`.
fn read_list(
    property: &Property,
    count_type: Scalar,
    (row, wanted): (usize, bool),
    body: &mut Body<'_>,
    read: &mut Row,
) -> Result<(), IoError> {
    let count = body.read(count_type)?;
    let Some(count) = as_index(count) else {
        return Err(body.error(format!("row {row}: bad list length")));
    };
    for _ in 0..count {
        let value = body.read(property.value)?;
        if wanted {
            let Some(index) = as_index(value) else {
                return Err(body.error(format!(
                    "face {row}: vertex index {value} is not a valid index"
                )));
            };
            read.polygon.push(index);
        }
    }
    Ok(())
}

fn read_vertex_property(property: &Property, value: f64, ours: bool, read: &mut Row) {
    match property.name.as_str() {
        "x" => read.position[0] = value as f32,
        "y" => read.position[1] = value as f32,
        "z" => read.position[2] = value as f32,
        "red" => read.colour[0] = colour_channel(value, property.value),
        "green" => read.colour[1] = colour_channel(value, property.value),
        "blue" => read.colour[2] = colour_channel(value, property.value),
        "flags" if ours => read.flags = as_index(value).unwrap_or(0),
        other => {
            if let Some(k) = BRDF_PROPERTIES.iter().position(|b| *b == other) {
                read.brdf[k] = value as f32;
            }
        }
    }
}

/// A colour channel as linear albedo: integers scaled by their type's largest value, floats
/// taken in [0, 1]; both read as sRGB, which is what scanners and paint tools store.
fn colour_channel(value: f64, scalar: Scalar) -> f32 {
    let encoded = match scalar {
        Scalar::U8 | Scalar::I8 => value / 255.0,
        Scalar::U16 | Scalar::I16 => value / 65535.0,
        Scalar::U32 | Scalar::I32 => value / u32::MAX as f64,
        Scalar::F32 | Scalar::F64 => value,
    };
    let c = if encoded.is_nan() {
        0.0
    } else {
        encoded.clamp(0.0, 1.0)
    } as f32;
    srgb_to_linear(c)
}

/// A name per layer: those the header's comments give, `layerN` for the rest. Named layers
/// count even when no face uses them any more.
fn layer_names(named: &[(u32, String)], face_layers: &[LayerId]) -> Vec<String> {
    let named_count = named
        .iter()
        .map(|(id, _)| id + 1)
        .filter(|&n| n <= MAX_LAYERS);
    let layer_count = face_layers
        .iter()
        .map(|&l| l + 1)
        .chain(named_count)
        .max()
        .unwrap_or(0);
    (0..layer_count)
        .map(|l| {
            named
                .iter()
                .find(|(id, _)| *id == l)
                .map(|(_, n)| n.clone())
                .unwrap_or_else(|| format!("layer{l}"))
        })
        .collect()
}

/// Writes the live mesh as binary little-endian PLY.
pub fn write_ply(mesh: &Mesh, out: &mut impl Write) -> io::Result<()> {
    write_ply_with(mesh, &[], out)
}

/// [`write_ply`] with the layers whose proximity policy is fuse marked in the header
/// (`comment slayer fuse ID`), so that the file keeps them.
pub fn write_ply_with(
    mesh: &Mesh,
    fuse_layers: &[LayerId],
    out: &mut impl Write,
) -> io::Result<()> {
    let mut file_index = vec![INVALID; mesh.vertex_count()];
    let mut live_vertices = 0u32;
    for (v, index) in file_index.iter_mut().enumerate() {
        if mesh.is_vertex_live(v as u32) {
            *index = live_vertices;
            live_vertices += 1;
        }
    }
    let live_faces = mesh.live_face_count();
    writeln!(out, "ply")?;
    writeln!(out, "format binary_little_endian 1.0")?;
    writeln!(out, "comment written by slayer")?;
    for (id, layer_name) in mesh.layer_names().iter().enumerate() {
        writeln!(out, "comment slayer layer {id} {layer_name}")?;
    }
    for id in fuse_layers {
        writeln!(out, "comment slayer fuse {id}")?;
    }
    writeln!(out, "element vertex {live_vertices}")?;
    for p in ["x", "y", "z", "nx", "ny", "nz"]
        .iter()
        .chain(&BRDF_PROPERTIES)
    {
        writeln!(out, "property float {p}")?;
    }
    // The diffuse albedo again as 8-bit sRGB, so other tools show the colours.
    for channel in ["red", "green", "blue"] {
        writeln!(out, "property uchar {channel}")?;
    }
    writeln!(out, "property uint layer")?;
    writeln!(out, "property uint flags")?;
    writeln!(out, "element face {live_faces}")?;
    writeln!(out, "property list uchar uint vertex_indices")?;
    writeln!(out, "property uint layer")?;
    writeln!(out, "end_header")?;
    // Rows gathered in a chunk at a time: the file is streamed, never held whole.
    let mut buffer: Vec<u8> = Vec::with_capacity(WRITE_CHUNK + 256);
    for v in (0..mesh.vertex_count()).filter(|&v| file_index[v] != INVALID) {
        let p = mesh.positions()[v];
        let n = mesh.normals()[v];
        for value in [p.x, p.y, p.z, n.x, n.y, n.z]
            .into_iter()
            .chain(mesh.brdfs()[v].as_array())
        {
            buffer.extend_from_slice(&value.to_le_bytes());
        }
        for channel in mesh.brdfs()[v].diffuse {
            buffer.push((linear_to_srgb(channel) * 255.0).round() as u8);
        }
        buffer.extend_from_slice(&mesh.vertex_layers()[v].to_le_bytes());
        let persistent = mesh.flags()[v] & VertexFlags::PERSISTENT;
        buffer.extend_from_slice(&persistent.bits().to_le_bytes());
        flush_chunk(out, &mut buffer)?;
    }
    for (t, &layer) in mesh.faces().iter().zip(mesh.face_layers()) {
        if t[0] == INVALID {
            continue;
        }
        buffer.push(3);
        for &v in t {
            buffer.extend_from_slice(&file_index[v as usize].to_le_bytes());
        }
        buffer.extend_from_slice(&layer.to_le_bytes());
        flush_chunk(out, &mut buffer)?;
    }
    out.write_all(&buffer)
}
