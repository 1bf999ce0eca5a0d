//! glTF 2.0 in (`.glb` and `.gltf`), what sculpting apps exchange. The `gltf` crate parses and
//! validates; every node of the scene with a mesh becomes a layer named after it, its
//! triangles (strips and fans too) taken through the node's transform and turned from glTF's
//! Y-up to slayer's Z-up. glTF splits vertices at UV and normal seams: they are welded again.
//! A vertex's BRDF comes from slayer's own attributes (`COLOR_0` diffuse, `_SPECULAR`,
//! `_ROUGHNESS`) where the file has them, else from `COLOR_0` and the material's
//! metallic-roughness factors. [`super::gltf_write`] writes the same shape back.

use ::gltf::mesh::{Mode, Semantic};
use ::gltf::{Document, Node, Primitive};
use base64::Engine;
use glam::{Mat4, Vec3};

use super::IoError;
use super::import::{Parsed, counted};
use super::obj::LibraryReader;
use super::weld::SoupBuilder;
use crate::mesh::{Brdf, LayerId};

/// glTF's Y-up point as slayer's Z-up one: a quarter turn about X, exact in floats (a swap
/// and a negation), so a round trip gives the same bits.
pub(super) fn from_y_up(p: Vec3) -> Vec3 {
    Vec3::new(p.x, -p.z, p.y)
}

/// Parses glTF bytes (`name` in messages); `files` reads buffers a `.gltf` names beside it.
pub(crate) fn parse_gltf(
    bytes: &[u8],
    name: &str,
    files: LibraryReader<'_>,
) -> Result<Parsed, IoError> {
    let fail = |message: String| IoError::parse(name, None, message);
    let file = ::gltf::Gltf::from_slice(bytes).map_err(|e| fail(format!("not glTF 2.0: {e}")))?;
    let buffers = file
        .document
        .buffers()
        .map(|buffer| buffer_bytes(&buffer, file.blob.as_deref(), files))
        .collect::<Result<Vec<_>, String>>()
        .map_err(fail)?;
    let mut builder = SoupBuilder::default();
    let mut not_kept = NotKept::default();
    for (node, world) in mesh_nodes(&file.document) {
        let Some(mesh) = node.mesh() else { continue };
        let layer_name = node
            .name()
            .or(mesh.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("layer{}", builder.layer_names.len()));
        let layer = builder.layer(layer_name);
        for primitive in mesh.primitives() {
            not_kept.note(&primitive);
            read_primitive(&primitive, (world, layer), &buffers, &mut builder).map_err(fail)?;
        }
    }
    not_kept.note_document(&file.document);
    if is_ours(&file.document) {
        // Ours are the mesh's own normals.
        not_kept.normals = 0;
    }
    builder.report.not_kept = not_kept.items();
    Ok(builder.finish())
}

/// A buffer's bytes: the GLB's binary chunk, a base64 `data:` URI, or a file beside the
/// `.gltf`; refused when shorter than the buffer says.
fn buffer_bytes(
    buffer: &::gltf::Buffer<'_>,
    blob: Option<&[u8]>,
    files: LibraryReader<'_>,
) -> Result<Vec<u8>, String> {
    let bytes = match buffer.source() {
        ::gltf::buffer::Source::Bin => blob
            .ok_or("the buffer names the GLB's binary chunk, which is missing")?
            .to_vec(),
        ::gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
            Some(data) => {
                let (_, encoded) = data
                    .split_once(";base64,")
                    .ok_or("a data URI that is not base64")?;
                base64::engine::general_purpose::STANDARD
                    .decode(encoded)
                    .map_err(|e| format!("a data URI that is not base64: {e}"))?
            }
            None => files(uri).map_err(|why| format!("buffer `{uri}` not read: {why}"))?,
        },
    };
    if bytes.len() < buffer.length() {
        return Err(format!(
            "buffer {} holds {} bytes of the {} it says",
            buffer.index(),
            bytes.len(),
            buffer.length()
        ));
    }
    Ok(bytes)
}

/// Every node of the scene (the default one, else the first, else every root) with its world
/// transform, parents before children.
fn mesh_nodes(document: &Document) -> Vec<(Node<'_>, Mat4)> {
    let roots: Vec<Node<'_>> = match document.default_scene().or(document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let children: Vec<usize> = document
                .nodes()
                .flat_map(|n| n.children().map(|c| c.index()))
                .collect();
            document
                .nodes()
                .filter(|n| !children.contains(&n.index()))
                .collect()
        }
    };
    let mut found = Vec::new();
    // The crate's validation refuses cycles, but a depth bound costs nothing.
    let mut stack: Vec<(Node<'_>, Mat4, usize)> =
        roots.into_iter().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if depth < 64 {
            stack.extend(node.children().map(|c| (c, world, depth + 1)));
        }
        found.push((node, world));
    }
    found.sort_by_key(|(node, _)| node.index());
    found
}

/// Written by slayer ([`super::gltf_write::GENERATOR`]).
fn is_ours(document: &Document) -> bool {
    let asset = &document.as_json().asset;
    asset.generator.as_deref() == Some(super::gltf_write::GENERATOR)
}

/// One primitive's triangles into `builder`, on `layer`, through `world`.
fn read_primitive(
    primitive: &Primitive<'_>,
    (world, layer): (Mat4, LayerId),
    buffers: &[Vec<u8>],
    builder: &mut SoupBuilder,
) -> Result<(), String> {
    let data = |b: ::gltf::Buffer<'_>| buffers.get(b.index()).map(Vec::as_slice);
    let reader = primitive.reader(data);
    let Some(positions) = reader.read_positions() else {
        return Ok(());
    };
    // The identity is skipped, not applied: `-0 + 0` is `+0`, and a round trip keeps bits.
    let place = |p: Vec3| {
        if world == Mat4::IDENTITY {
            p
        } else {
            world.transform_point3(p)
        }
    };
    let points: Vec<Vec3> = positions
        .map(|p| from_y_up(place(Vec3::from_array(p))))
        .collect();
    let brdfs = vertex_brdfs(primitive, buffers, points.len());
    let indices: Vec<u32> = match reader.read_indices() {
        Some(indices) => indices.into_u32().collect(),
        None => (0..points.len() as u32).collect(),
    };
    // Points in the file's order (so a round trip keeps vertex numbers), welded.
    let welded: Vec<u32> = points
        .iter()
        .enumerate()
        .map(|(i, &p)| builder.point(p, brdfs.as_ref().map(|b| b[i]), layer))
        .collect();
    // A mirroring transform turns the winding inside out: turn it back.
    let mirrored = world.determinant() < 0.0;
    for mut tri in triangles(primitive.mode(), &indices) {
        if mirrored {
            tri.swap(1, 2);
        }
        let face: Option<Vec<u32>> = tri
            .iter()
            .map(|&i| welded.get(i as usize).copied())
            .collect();
        let Some(&[a, b, c]) = face.as_deref() else {
            let count = points.len();
            return Err(format!("a triangle's index is past the {count} vertices"));
        };
        builder.face([a, b, c], layer);
    }
    Ok(())
}

/// The triangles of a primitive's indices: lists, strips and fans; points and lines have none.
fn triangles(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::Triangles => indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
        Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
            .map(|k| {
                let t = [indices[k], indices[k + 1], indices[k + 2]];
                if k % 2 == 0 { t } else { [t[1], t[0], t[2]] }
            })
            .collect(),
        Mode::TriangleFan => (1..indices.len().saturating_sub(1))
            .map(|k| [indices[0], indices[k], indices[k + 1]])
            .collect(),
        _ => Vec::new(),
    }
}

/// Each vertex's BRDF: slayer's own attributes where present; else the material's base colour
/// (times `COLOR_0`) split by its metallic factor into diffuse and specular, and its
/// roughness factor (glTF's perceptual roughness is our linearized roughness). `None` for a
/// primitive with neither colours nor a material.
fn vertex_brdfs(primitive: &Primitive<'_>, buffers: &[Vec<u8>], count: usize) -> Option<Vec<Brdf>> {
    let data = |b: ::gltf::Buffer<'_>| buffers.get(b.index()).map(Vec::as_slice);
    let reader = primitive.reader(data);
    let colours: Option<Vec<[f32; 3]>> = reader.read_colors(0).map(|c| c.into_rgb_f32().collect());
    let extra = |name: &str| primitive.get(&Semantic::Extras(name.to_string()));
    let specular: Option<Vec<[f32; 3]>> = extra("SPECULAR")
        .and_then(|a| ::gltf::accessor::Iter::<[f32; 3]>::new(a, data))
        .map(Iterator::collect);
    let roughness: Option<Vec<f32>> = extra("ROUGHNESS")
        .and_then(|a| ::gltf::accessor::Iter::<f32>::new(a, data))
        .map(Iterator::collect);
    let material = primitive.material();
    let has_material = material.index().is_some();
    if colours.is_none() && specular.is_none() && !has_material {
        return None;
    }
    let pbr = material.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    // Without a material glTF's default is a rough metal; colours alone (a scan) mean paint.
    let (metallic, default_roughness) = match has_material {
        true => (
            pbr.metallic_factor().clamp(0.0, 1.0),
            pbr.roughness_factor(),
        ),
        false => (0.0, Brdf::CLAY.roughness),
    };
    let at = |v: usize| {
        let tint = colours
            .as_ref()
            .and_then(|c| c.get(v))
            .copied()
            .unwrap_or([1.0; 3]);
        let base = [r * tint[0], g * tint[1], b * tint[2]];
        let own = specular.as_ref().and_then(|s| s.get(v)).copied();
        let diffuse = match own {
            Some(_) => tint,
            None => base.map(|c| c * (1.0 - metallic)),
        };
        let dielectric = Brdf::CLAY.specular[0];
        let specular = own.unwrap_or(base.map(|c| dielectric + (c - dielectric) * metallic));
        let rough = roughness
            .as_ref()
            .and_then(|s| s.get(v))
            .copied()
            .unwrap_or(default_roughness);
        Brdf::new(diffuse, specular, rough).clamped()
    };
    Some((0..count).map(at).collect())
}

/// What a glTF holds that a slayer mesh does not keep.
#[derive(Default)]
struct NotKept {
    texture_coordinates: usize,
    normals: usize,
    tangents: usize,
    skins: usize,
    morph_targets: usize,
    lines_and_points: usize,
    textures: usize,
    animations: usize,
}

impl NotKept {
    fn note(&mut self, primitive: &Primitive<'_>) {
        for (semantic, _) in primitive.attributes() {
            match semantic {
                Semantic::TexCoords(_) => self.texture_coordinates += 1,
                Semantic::Normals => self.normals += 1,
                Semantic::Tangents => self.tangents += 1,
                Semantic::Joints(_) | Semantic::Weights(_) => self.skins += 1,
                _ => {}
            }
        }
        self.morph_targets += primitive.morph_targets().len();
        if !matches!(
            primitive.mode(),
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.lines_and_points += 1;
        }
    }

    fn note_document(&mut self, document: &Document) {
        self.textures = document.textures().len();
        self.animations = document.animations().len();
    }

    fn items(&self) -> Vec<String> {
        counted(&[
            (self.texture_coordinates, "texture coordinate sets"),
            (self.normals, "normal sets (recomputed)"),
            (self.tangents, "tangent sets"),
            (self.skins, "skinning attributes"),
            (self.morph_targets, "morph targets"),
            (self.lines_and_points, "line or point primitives"),
            (self.textures, "textures"),
            (self.animations, "animations"),
        ])
    }
}
