//! Wavefront OBJ. tobj parses and triangulates; a pre-scan of our own finds what tobj would
//! reject or mis-handle (bad numbers, indices out of range or zero, non-finite values) and names
//! the line, since tobj's errors carry none. Each object or group becomes a layer, and vertices
//! at identical positions within a layer are welded.

use std::io::{self, BufRead, Write};

use glam::Vec3;
use rustc_hash::FxHashMap;

use super::IoError;
use crate::mesh::{Brdf, INVALID, LayerId, MAX_COORDINATE, Mesh};

/// What parsing found besides the mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ObjReport {
    pub non_finite_vertices: usize,
    pub first_non_finite_line: Option<usize>,
    pub welded_vertices: usize,
}

/// Parses OBJ bytes into a mesh (`name` is used in messages).
pub fn parse_obj(bytes: &[u8], name: &str) -> Result<(Mesh, ObjReport), IoError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        IoError::parse(name, Some(line), "not a text file (invalid UTF-8)")
    })?;
    let (mut report, file_positions) = prescan(text, name)?;
    let models = load_models(text, name)?;

    // tobj numbers each object's vertices in the order faces first use them; putting them back
    // in file order keeps vertex numbers stable across a write and a read.
    let mut file_order: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    for (i, p) in file_positions.iter().enumerate() {
        if !p.is_nan() {
            file_order.entry(weld_key(*p)).or_insert(i as u32);
        }
    }

    let mut positions: Vec<Vec3> = Vec::new();
    let mut faces: Vec<[u32; 3]> = Vec::new();
    let mut face_layers: Vec<LayerId> = Vec::new();
    let mut layer_names: Vec<String> = Vec::new();
    for model in &models {
        if model.mesh.indices.len() < 3 {
            continue;
        }
        let layer = layer_names.len() as LayerId;
        layer_names.push(if model.name.is_empty() || model.name == "unnamed_object" {
            format!("layer{layer}")
        } else {
            model.name.clone()
        });
        let (points, local_to_global) =
            weld(&model.mesh, &file_order, positions.len(), &mut report);
        positions.extend(points);
        for face in model_faces(model, &local_to_global, name)? {
            faces.push(face);
            face_layers.push(layer);
        }
    }
    if faces.is_empty() {
        return Err(IoError::parse(name, None, "no faces"));
    }
    let mesh = Mesh::new(positions.clone(), faces, face_layers, layer_names)
        .map_err(|e| IoError::building(name, e, &positions))?;
    Ok((mesh, report))
}

/// The file's objects through tobj, triangulated (points and lines ignored); an error names
/// the line tobj stopped at.
fn load_models(text: &str, name: &str) -> Result<Vec<tobj::Model>, IoError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = LineCounter {
        inner: io::BufReader::new(text.as_bytes()),
        lines: 0,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| IoError::parse(name, Some(reader.lines.max(1)), format!("{e}")))?;
    Ok(models)
}

/// One object's points welded by exact bit pattern (+0 and −0 are one point; NaN never welds),
/// in file order (`file_order`: each point's first line); and each of tobj's vertices' number
/// in the mesh, the welded points numbered from `base`.
fn weld(
    mesh: &tobj::Mesh,
    file_order: &FxHashMap<[u32; 3], u32>,
    base: usize,
    report: &mut ObjReport,
) -> (Vec<Vec3>, Vec<u32>) {
    let mut welded: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    let mut local_to_welded = Vec::with_capacity(mesh.positions.len() / 3);
    let mut welded_points: Vec<(u64, Vec3)> = Vec::new();
    for (i, p) in mesh.positions.chunks_exact(3).enumerate() {
        let p = Vec3::new(p[0], p[1], p[2]);
        let unmatched = (1u64 << 32) + i as u64;
        let key = (!p.is_nan()).then(|| weld_key(p));
        let order = key
            .and_then(|k| file_order.get(&k))
            .map_or(unmatched, |&o| o as u64);
        let existing = key.and_then(|k| welded.get(&k).copied());
        let id = existing.unwrap_or_else(|| {
            welded_points.push((order, p));
            let id = (welded_points.len() - 1) as u32;
            if let Some(k) = key {
                welded.insert(k, id);
            }
            id
        });
        if existing.is_some() {
            report.welded_vertices += 1;
        }
        local_to_welded.push(id);
    }
    let mut by_order: Vec<u32> = (0..welded_points.len() as u32).collect();
    by_order.sort_by_key(|&id| welded_points[id as usize].0);
    let mut welded_to_global = vec![0u32; welded_points.len()];
    let mut points = Vec::with_capacity(welded_points.len());
    for &id in &by_order {
        welded_to_global[id as usize] = (base + points.len()) as u32;
        points.push(welded_points[id as usize].1);
    }
    let local_to_global = local_to_welded
        .iter()
        .map(|&id| welded_to_global[id as usize])
        .collect();
    (points, local_to_global)
}

/// An object's triangles in the mesh's numbering; an index out of range or a corner used
/// twice is an error naming the object and triangle.
fn model_faces(
    model: &tobj::Model,
    local_to_global: &[u32],
    name: &str,
) -> Result<Vec<[u32; 3]>, IoError> {
    let fail = |message: String| Err(IoError::parse(name, None, message));
    let mut faces = Vec::with_capacity(model.mesh.indices.len() / 3);
    for (k, tri) in model.mesh.indices.chunks_exact(3).enumerate() {
        let face = [tri[0], tri[1], tri[2]]
            .map(|i| local_to_global.get(i as usize).copied().unwrap_or(INVALID));
        if face.contains(&INVALID) {
            return fail(format!(
                "object `{}`: triangle {k} has a vertex index out of range",
                model.name
            ));
        }
        if face[0] == face[1] || face[1] == face[2] || face[0] == face[2] {
            return fail(format!(
                "object `{}`: triangle {k} uses the same point twice (coincident corners)",
                model.name
            ));
        }
        faces.push(face);
    }
    Ok(faces)
}

/// Checks every `v` and `f` line for what tobj would reject without a line number or accept
/// wrongly: unparsable or missing numbers, index 0, indices past the vertices defined so far.
fn prescan(text: &str, name: &str) -> Result<(ObjReport, Vec<Vec3>), IoError> {
    let mut report = ObjReport::default();
    let mut file_positions = Vec::new();
    let (mut positions, mut texcoords, mut normals) = (0usize, 0usize, 0usize);
    for (number, line) in text.lines().enumerate() {
        let number = number + 1;
        let fail = |message: String| Err(IoError::parse(name, Some(number), message));
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let mut coordinates = [0f32; 3];
                for (axis, slot) in coordinates.iter_mut().enumerate() {
                    match words.next().map(str::parse::<f32>) {
                        Some(Ok(value)) => *slot = value,
                        Some(Err(_)) => {
                            return fail(format!("vertex coordinate {axis} is not a number"));
                        }
                        None => return fail("vertex needs three coordinates".into()),
                    }
                }
                if coordinates.iter().any(|c| !c.is_finite()) {
                    report.non_finite_vertices += 1;
                    report.first_non_finite_line.get_or_insert(number);
                } else if coordinates.iter().any(|c| c.abs() > MAX_COORDINATE) {
                    return fail(format!(
                        "vertex coordinate beyond the supported range ±{MAX_COORDINATE:e}"
                    ));
                }
                positions += 1;
                file_positions.push(Vec3::from_array(coordinates));
            }
            Some("vt") => texcoords += 1,
            Some("vn") => normals += 1,
            Some("f") => {
                let mut corners = 0;
                for word in words {
                    corners += 1;
                    let counts = [
                        ("vertex", positions),
                        ("texture", texcoords),
                        ("normal", normals),
                    ];
                    for (field, (what, defined)) in word.split('/').zip(counts) {
                        if field.is_empty() && what != "vertex" {
                            continue;
                        }
                        let index = match field.parse::<i64>() {
                            Ok(i) => i,
                            Err(_) => {
                                return fail(format!(
                                    "face {what} index `{field}` is not an integer"
                                ));
                            }
                        };
                        let in_range = if index > 0 {
                            index as u64 <= defined as u64
                        } else {
                            index != 0 && index.unsigned_abs() <= defined as u64
                        };
                        if !in_range {
                            return fail(format!(
                                "face {what} index {index} is out of range ({defined} defined so far)"
                            ));
                        }
                    }
                    if word.split('/').count() > 3 {
                        return fail(format!("face corner `{word}` has more than three indices"));
                    }
                }
                if corners < 3 {
                    return fail(format!("face has {corners} corners; at least 3 are needed"));
                }
            }
            Some("o") | Some("g") if words.next().is_none() => {
                return fail("object or group without a name".into());
            }
            _ => {}
        }
    }
    Ok((report, file_positions))
}

/// Welding identity of a point: its bits, with -0 folded into +0.
fn weld_key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// Counts lines as tobj reads them, to put a line number on tobj's errors.
struct LineCounter<R> {
    inner: R,
    lines: usize,
}

impl<R: BufRead> io::Read for LineCounter<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.lines += buf[..n].iter().filter(|&&b| b == b'\n').count();
        Ok(n)
    }
}

impl<R: BufRead> BufRead for LineCounter<R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        self.inner.fill_buf()
    }

    fn consume(&mut self, amount: usize) {
        if let Ok(buf) = self.inner.fill_buf() {
            let n = amount.min(buf.len());
            self.lines += buf[..n].iter().filter(|&&b| b == b'\n').count();
        }
        self.inner.consume(amount);
    }
}

/// Writes the live mesh as OBJ: one `o` per layer, its vertices then its faces.
pub fn write_obj(mesh: &Mesh, out: &mut impl Write) -> io::Result<()> {
    write_obj_with_materials(mesh, out, None)
}

/// [`write_obj`], naming the material library `library` (a file name beside the OBJ, written
/// by [`write_mtl`]) in a `mtllib` line and giving each layer its material with `usemtl`.
pub fn write_obj_with_materials(
    mesh: &Mesh,
    out: &mut impl Write,
    library: Option<&str>,
) -> io::Result<()> {
    let live_faces = mesh.live_face_count();
    writeln!(
        out,
        "# slayer mesh: {} vertices, {} faces, {} layers",
        mesh.live_vertex_count(),
        live_faces,
        mesh.layer_count()
    )?;
    if let Some(library) = library {
        writeln!(out, "mtllib {library}")?;
    }
    let mut file_index = vec![0u32; mesh.vertex_count()];
    let mut next_index = 1u32;
    for (layer, layer_name) in mesh.layer_names().iter().enumerate() {
        let layer = layer as LayerId;
        let has_faces = mesh
            .faces()
            .iter()
            .zip(mesh.face_layers())
            .any(|(t, &l)| l == layer && t[0] != INVALID);
        if !has_faces {
            continue;
        }
        writeln!(out, "o {}", sanitize_name(layer_name))?;
        if library.is_some() {
            // Before the layer's faces, so that readers keep one object per layer.
            writeln!(out, "usemtl {}", sanitize_name(layer_name))?;
        }
        for (v, p) in mesh.positions().iter().enumerate() {
            if mesh.vertex_layers()[v] == layer && mesh.is_vertex_live(v as u32) {
                writeln!(out, "v {} {} {}", p.x, p.y, p.z)?;
                file_index[v] = next_index;
                next_index += 1;
            }
        }
        for (t, &l) in mesh.faces().iter().zip(mesh.face_layers()) {
            if l == layer && t[0] != INVALID {
                let [a, b, c] = t.map(|v| file_index[v as usize]);
                writeln!(out, "f {a} {b} {c}")?;
            }
        }
    }
    Ok(())
}

/// Each layer with faces, with its material: the mean BRDF of its live vertices. The
/// parametrization is linear, so the mean is the layer's average material; a layer nobody has
/// painted gets exactly its default (generated scenes give each layer a preset).
pub fn layer_materials(mesh: &Mesh) -> Vec<(LayerId, String, Brdf)> {
    let mut sums = vec![[0f64; 7]; mesh.layer_count()];
    let mut counts = vec![0usize; mesh.layer_count()];
    let mut has_faces = vec![false; mesh.layer_count()];
    for (t, &l) in mesh.faces().iter().zip(mesh.face_layers()) {
        if t[0] != INVALID {
            has_faces[l as usize] = true;
        }
    }
    for (v, brdf) in mesh.brdfs().iter().enumerate() {
        if !mesh.is_vertex_live(v as u32) {
            continue;
        }
        let layer = mesh.vertex_layers()[v] as usize;
        for (sum, value) in sums[layer].iter_mut().zip(brdf.as_array()) {
            *sum += value as f64;
        }
        counts[layer] += 1;
    }
    (0..mesh.layer_count())
        .filter(|&l| has_faces[l])
        .map(|l| {
            let n = counts[l].max(1) as f64;
            let mean = Brdf::from_array(sums[l].map(|s| (s / n) as f32));
            (l as LayerId, sanitize_name(&mesh.layer_names()[l]), mean)
        })
        .collect()
}

/// Writes a Wavefront material library with one `newmtl` per layer ([`layer_materials`]):
/// `Kd` the diffuse albedo, `Ks` the specular albedo, `Ns` the Blinn–Phong exponent of the
/// linearized roughness ([`crate::mesh::blinn_exponent`]).
pub fn write_mtl(mesh: &Mesh, out: &mut impl Write) -> io::Result<()> {
    writeln!(out, "# slayer materials: one per layer")?;
    for (_, name, brdf) in layer_materials(mesh) {
        writeln!(out)?;
        writeln!(out, "newmtl {name}")?;
        if let Some(preset) = crate::material::PRESETS
            .iter()
            .find(|m| close(&m.brdf, &brdf))
        {
            writeln!(out, "# preset {}", preset.name)?;
        }
        writeln!(out, "# linearized roughness {}", brdf.roughness)?;
        let [r, g, b] = brdf.diffuse;
        writeln!(out, "Kd {r} {g} {b}")?;
        let [r, g, b] = brdf.specular;
        writeln!(out, "Ks {r} {g} {b}")?;
        writeln!(out, "Ns {}", brdf.blinn_exponent())?;
        writeln!(out, "illum 2")?;
    }
    Ok(())
}

fn close(a: &Brdf, b: &Brdf) -> bool {
    a.as_array()
        .iter()
        .zip(b.as_array())
        .all(|(x, y)| (x - y).abs() <= 1e-5)
}

/// OBJ names end at whitespace.
fn sanitize_name(name: &str) -> String {
    let cleaned: String = name
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect();
    if cleaned.is_empty() {
        "layer".into()
    } else {
        cleaned
    }
}
