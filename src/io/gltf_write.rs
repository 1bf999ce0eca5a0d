//! glTF 2.0 out: `.glb` (one binary file) or `.gltf` (JSON with the buffer inline as a base64
//! `data:` URI, so it is still one file). One node and mesh per layer, named after it; each
//! vertex's position and normal (turned from slayer's Z-up to glTF's Y-up), its BRDF as
//! `COLOR_0` (the diffuse albedo, linear as glTF's colours are) and the application-specific
//! `_SPECULAR` and `_ROUGHNESS`; a metallic-roughness material per layer approximating the
//! layer's mean BRDF, for viewers that read materials only.

use std::io::{self, Write};

use base64::Engine;
use glam::Vec3;
use serde_json::{Value, json};

use super::mtl::layer_materials;
use crate::mesh::{Brdf, INVALID, LayerId, Mesh};

/// `asset.generator` of our files: what tells the reader the normals are the mesh's own.
pub const GENERATOR: &str = "slayer";

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// slayer's Z-up point as glTF's Y-up one: the inverse of [`super::gltf::from_y_up`].
fn to_y_up(p: Vec3) -> Vec3 {
    Vec3::new(p.x, p.z, -p.y)
}

/// The JSON document and the binary buffer it describes, built up accessor by accessor.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    /// Appends `values` (each `width` floats) as a buffer view and an accessor; returns the
    /// accessor's index. `bounds` adds the `min`/`max` glTF requires of positions.
    fn floats(&mut self, values: &[f32], width: usize, bounds: bool) -> usize {
        let kind = ["SCALAR", "VEC2", "VEC3", "VEC4"][width - 1];
        let mut accessor = json!({
            "componentType": FLOAT,
            "count": values.len() / width,
            "type": kind,
        });
        if bounds {
            let (mut min, mut max) = (vec![f32::INFINITY; width], vec![f32::NEG_INFINITY; width]);
            for row in values.chunks_exact(width) {
                for (k, &v) in row.iter().enumerate() {
                    min[k] = min[k].min(v);
                    max[k] = max[k].max(v);
                }
            }
            accessor["min"] = json!(min);
            accessor["max"] = json!(max);
        }
        let bytes: &[u8] = bytemuck::cast_slice(values);
        self.push(bytes, ARRAY_BUFFER, accessor)
    }

    fn indices(&mut self, indices: &[u32]) -> usize {
        let accessor = json!({
            "componentType": UNSIGNED_INT,
            "count": indices.len(),
            "type": "SCALAR",
        });
        self.push(
            bytemuck::cast_slice(indices),
            ELEMENT_ARRAY_BUFFER,
            accessor,
        )
    }

    fn push(&mut self, bytes: &[u8], target: u32, mut accessor: Value) -> usize {
        // Every view starts 4-byte aligned (all our components are 4 bytes).
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": offset,
            "byteLength": bytes.len(),
            "target": target,
        }));
        accessor["bufferView"] = json!(self.views.len() - 1);
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }
}

/// A layer's live vertices in the mesh's order (so a round trip keeps vertex numbers) and its
/// faces in their numbering.
fn layer_rows(mesh: &Mesh, layer: LayerId) -> (Vec<usize>, Vec<u32>) {
    let faces = || {
        mesh.faces()
            .iter()
            .zip(mesh.face_layers())
            .filter(move |(tri, l)| **l == layer && tri[0] != INVALID)
            .map(|(tri, _)| tri)
    };
    let mut local = vec![INVALID; mesh.vertex_count()];
    for tri in faces() {
        for &v in tri {
            local[v as usize] = 0;
        }
    }
    let mut vertices = Vec::new();
    for (v, slot) in local.iter_mut().enumerate() {
        if *slot != INVALID {
            *slot = vertices.len() as u32;
            vertices.push(v);
        }
    }
    let indices = faces()
        .flat_map(|tri| tri.map(|v| local[v as usize]))
        .collect();
    (vertices, indices)
}

/// The metallic-roughness material nearest a BRDF: specular far above a dielectric's 4 % is
/// metal, whose base colour is its specular colour.
fn material(name: &str, brdf: &Brdf) -> Value {
    let luminance = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let metallic = ((luminance(brdf.specular) - 0.04) / 0.96).clamp(0.0, 1.0);
    let base: Vec<f32> = (0..3)
        .map(|k| brdf.diffuse[k] * (1.0 - metallic) + brdf.specular[k] * metallic)
        .chain([1.0])
        .collect();
    json!({
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": base,
            "metallicFactor": metallic,
            "roughnessFactor": brdf.roughness.clamp(0.0, 1.0),
        },
        "doubleSided": true,
    })
}

/// The document and its buffer.
fn document(mesh: &Mesh) -> (Value, Vec<u8>) {
    let mut builder = Builder::default();
    let (mut nodes, mut meshes, mut materials) = (Vec::new(), Vec::new(), Vec::new());
    for (layer, name, mean) in layer_materials(mesh) {
        let (vertices, indices) = layer_rows(mesh, layer);
        let flat = |f: &dyn Fn(usize) -> [f32; 3]| -> Vec<f32> {
            vertices.iter().flat_map(|&v| f(v)).collect()
        };
        let positions = flat(&|v| to_y_up(mesh.positions()[v]).to_array());
        let normals = flat(&|v| to_y_up(mesh.normals()[v]).to_array());
        let diffuse = flat(&|v| mesh.brdfs()[v].diffuse);
        let specular = flat(&|v| mesh.brdfs()[v].specular);
        let roughness: Vec<f32> = vertices
            .iter()
            .map(|&v| mesh.brdfs()[v].roughness)
            .collect();
        let attributes = json!({
            "POSITION": builder.floats(&positions, 3, true),
            "NORMAL": builder.floats(&normals, 3, false),
            "COLOR_0": builder.floats(&diffuse, 3, false),
            "_SPECULAR": builder.floats(&specular, 3, false),
            "_ROUGHNESS": builder.floats(&roughness, 1, false),
        });
        let indices = builder.indices(&indices);
        materials.push(material(&name, &mean));
        meshes.push(json!({
            "name": name,
            "primitives": [{
                "attributes": attributes,
                "indices": indices,
                "material": materials.len() - 1,
                "mode": 4,
            }],
        }));
        nodes.push(json!({ "name": mesh.layer_names()[layer as usize], "mesh": meshes.len() - 1 }));
    }
    let mut document = json!({
        "asset": { "version": "2.0", "generator": GENERATOR },
        "scene": 0,
        "scenes": [{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": builder.accessors,
        "bufferViews": builder.views,
        "buffers": [{ "byteLength": builder.bin.len() }],
    });
    if builder.bin.is_empty() {
        // A mesh with no faces: glTF allows no empty arrays and no empty buffer.
        for key in [
            "nodes",
            "meshes",
            "materials",
            "accessors",
            "bufferViews",
            "buffers",
        ] {
            document.as_object_mut().map(|d| d.remove(key));
        }
        document["scenes"] = json!([{}]);
    }
    (document, builder.bin)
}

/// Writes the live mesh as a binary glTF (`.glb`).
pub fn write_glb(mesh: &Mesh, out: &mut impl Write) -> io::Result<()> {
    let (document, mut bin) = document(mesh);
    let mut json = serde_json::to_vec(&document).map_err(io::Error::other)?;
    // Chunks are 4-byte aligned: JSON padded with spaces, the buffer with zeros.
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let total = u32::try_from(total).map_err(|_| io::Error::other("a GLB holds at most 4 GiB"))?;
    let mut bytes = Vec::with_capacity(total as usize);
    bytes.extend_from_slice(b"glTF");
    bytes.extend_from_slice(&2u32.to_le_bytes());
    bytes.extend_from_slice(&total.to_le_bytes());
    for (chunk, kind) in [(&json, b"JSON"), (&bin, b"BIN\0")] {
        bytes.extend_from_slice(&(chunk.len() as u32).to_le_bytes());
        bytes.extend_from_slice(kind);
        bytes.extend_from_slice(chunk);
    }
    out.write_all(&bytes)
}

/// Writes the live mesh as a `.gltf`: JSON, its buffer inline as a base64 `data:` URI.
pub fn write_gltf(mesh: &Mesh, out: &mut impl Write) -> io::Result<()> {
    let (mut document, bin) = document(mesh);
    let encoded = base64::engine::general_purpose::STANDARD.encode(&bin);
    document["buffers"][0]["uri"] =
        json!(format!("data:application/octet-stream;base64,{encoded}"));
    serde_json::to_writer_pretty(&mut *out, &document).map_err(io::Error::other)?;
    writeln!(out)
}
