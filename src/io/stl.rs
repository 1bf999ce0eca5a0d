//! STL, what 3-D printing takes: binary and ASCII in, binary out. STL stores each triangle's
//! three points on their own, so reading welds points at identical positions (by bit pattern,
//! as OBJ does). An ASCII file's `solid`s become layers; a binary file slayer wrote keeps each
//! face's layer in the attribute bytes, and says so in its header with the layers' names.

use std::io::{self, Write};

use glam::Vec3;

use super::import::Parsed;
use super::weld::SoupBuilder as Builder;
use super::{IoError, WRITE_CHUNK, flush_chunk};
use crate::mesh::{INVALID, LayerId, Mesh};

/// The start of the 80-byte header of a binary STL slayer wrote; the layer names follow,
/// separated by `|`.
const OWN_HEADER: &str = "slayer stl, attribute = layer; layers: ";
const HEADER_BYTES: usize = 80;
const TRIANGLE_BYTES: usize = 50;

/// Parses STL bytes, binary or ASCII (`name` is used in messages).
pub(crate) fn parse_stl(bytes: &[u8], name: &str) -> Result<Parsed, IoError> {
    let builder = match binary_count(bytes) {
        Some(count) => read_binary(bytes, count),
        None => read_ascii(bytes, name)?,
    };
    Ok(builder.finish())
}

/// The triangle count of a binary STL: the one its header gives when the size matches it.
/// An ASCII file that happens to have the right size still starts with `solid` and holds
/// `facet`; a binary one whose header starts with `solid` (many writers do that) does not.
fn binary_count(bytes: &[u8]) -> Option<usize> {
    let count = u32::from_le_bytes(bytes.get(HEADER_BYTES..HEADER_BYTES + 4)?.try_into().ok()?);
    let fits = HEADER_BYTES + 4 + count as usize * TRIANGLE_BYTES == bytes.len();
    let looks_ascii = bytes.starts_with(b"solid")
        && bytes
            .windows(5)
            .take(4096)
            .any(|w| w.eq_ignore_ascii_case(b"facet"));
    (fits && !looks_ascii).then_some(count as usize)
}

fn read_binary(bytes: &[u8], count: usize) -> Builder {
    let mut builder = Builder::default();
    let header = String::from_utf8_lossy(&bytes[..HEADER_BYTES]);
    let own_names: Option<Vec<String>> = header.strip_prefix(OWN_HEADER).map(|names| {
        names
            .trim_end_matches(['\0', ' '])
            .split('|')
            .map(str::to_string)
            .collect()
    });
    let float = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap_or([0; 4]));
    let mut attributes = 0usize;
    for t in 0..count {
        let at = HEADER_BYTES + 4 + t * TRIANGLE_BYTES;
        let corners: [Vec3; 3] = std::array::from_fn(|k| {
            Vec3::from_array(std::array::from_fn(|i| float(at + 12 + 12 * k + 4 * i)))
        });
        let attribute = u16::from_le_bytes([bytes[at + 48], bytes[at + 49]]);
        let layer = match &own_names {
            Some(_) => attribute as LayerId,
            None => {
                attributes += usize::from(attribute != 0);
                0
            }
        };
        while builder.layer_names.len() <= layer as usize {
            let l = builder.layer_names.len();
            let name = own_names
                .as_ref()
                .and_then(|n| n.get(l).cloned())
                .unwrap_or_else(|| format!("layer{l}"));
            builder.layer(name);
        }
        builder.triangle(corners, layer);
    }
    if own_names.is_none() {
        // Ours are the faces' own normals; another writer's may not be.
        let normals = format!("{count} facet normals (recomputed)");
        builder.report.not_kept.push(normals);
    }
    if attributes > 0 {
        builder
            .report
            .not_kept
            .push(format!("{attributes} triangles' attribute bytes (colour)"));
    }
    builder
}

fn read_ascii(bytes: &[u8], name: &str) -> Result<Builder, IoError> {
    let text = std::str::from_utf8(bytes).map_err(|_| {
        IoError::parse(
            name,
            None,
            "neither a binary STL (its size does not match its triangle count) nor text",
        )
    })?;
    let mut builder = Builder::default();
    let mut layer: Option<LayerId> = None;
    let mut corners: Vec<Vec3> = Vec::with_capacity(3);
    let mut normals = 0usize;
    for (number, line) in text.lines().enumerate() {
        let fail = |message: &str| IoError::parse(name, Some(number + 1), message);
        let mut words = line.split_whitespace();
        match words.next().map(str::to_ascii_lowercase).as_deref() {
            Some("solid") => {
                let solid: Vec<&str> = words.collect();
                let l = builder.layer_names.len();
                let named = if solid.is_empty() {
                    format!("layer{l}")
                } else {
                    solid.join("_")
                };
                layer = Some(builder.layer(named));
            }
            Some("facet") => {
                normals += 1;
                corners.clear();
            }
            Some("vertex") => {
                let coordinates: Vec<f32> = words
                    .map(str::parse::<f32>)
                    .collect::<Result<_, _>>()
                    .map_err(|_| fail("vertex coordinate is not a number"))?;
                let [x, y, z] = coordinates[..] else {
                    return Err(fail("vertex needs three coordinates"));
                };
                corners.push(Vec3::new(x, y, z));
            }
            Some("endfacet") => {
                let [a, b, c] = corners[..] else {
                    return Err(fail("a facet needs three vertices"));
                };
                let layer = match layer {
                    Some(l) => l,
                    None => return Err(fail("facet before `solid`")),
                };
                builder.triangle([a, b, c], layer);
            }
            Some("outer" | "endloop" | "endsolid") | None => {}
            Some(_) => return Err(fail("not an ASCII STL line")),
        }
    }
    builder
        .report
        .not_kept
        .push(format!("{normals} facet normals (recomputed)"));
    Ok(builder)
}

/// Writes the live mesh as binary STL: each face's normal and corners, its layer in the
/// attribute bytes, the layer names in the header (as many as fit in its 80 bytes).
pub fn write_stl(mesh: &Mesh, out: &mut impl Write) -> io::Result<()> {
    let names: Vec<String> = mesh
        .layer_names()
        .iter()
        .map(|n| n.replace(['|', '\0'], "_"))
        .collect();
    let mut header = format!("{OWN_HEADER}{}", names.join("|")).into_bytes();
    header.resize(HEADER_BYTES, 0);
    let live = mesh.live_face_count();
    let mut buffer = Vec::with_capacity(WRITE_CHUNK + HEADER_BYTES + TRIANGLE_BYTES);
    buffer.extend_from_slice(&header);
    buffer.extend_from_slice(&(live as u32).to_le_bytes());
    for (f, (tri, &layer)) in mesh.faces().iter().zip(mesh.face_layers()).enumerate() {
        if tri[0] == INVALID {
            continue;
        }
        let normal = mesh.face_normal(f);
        let corners = tri.map(|v| mesh.positions()[v as usize]);
        for p in std::iter::once(normal).chain(corners) {
            for c in p.to_array() {
                buffer.extend_from_slice(&c.to_le_bytes());
            }
        }
        buffer.extend_from_slice(&(layer.min(u16::MAX as u32) as u16).to_le_bytes());
        flush_chunk(out, &mut buffer)?;
    }
    out.write_all(&buffer)
}
