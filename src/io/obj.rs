//! Wavefront OBJ. tobj parses and triangulates; a pre-scan of our own finds what tobj would
//! reject or mis-handle (bad numbers, indices out of range or zero, non-finite values) and names
//! the line, since tobj's errors carry none. Each object or group becomes a layer (an object
//! tobj split at a material change is joined again), vertices at identical positions within a
//! layer are welded, and faces take the BRDF of their material (`usemtl`, from the `mtllib`
//! beside the file, [`super::mtl`]). What an OBJ holds that a mesh does not keep (texture
//! coordinates, normals, lines) is counted in the import report.

use std::cell::RefCell;
use std::io::{self, BufRead, Write};

use glam::Vec3;
use rustc_hash::FxHashMap;

use super::IoError;
use super::import::{ImportReport, Parsed, counted};
use super::mtl::{material_brdf, material_not_kept, sanitize_name};
use super::weld::weld_key;
use crate::material::srgb_to_linear;
use crate::mesh::{Brdf, INVALID, LayerId, MAX_COORDINATE, Mesh};

/// Reads a material library an OBJ names (`mtllib NAME`): its bytes, or why not.
pub type LibraryReader<'a> = &'a dyn Fn(&str) -> Result<Vec<u8>, String>;

/// Parses OBJ bytes (`name` is used in messages); `library` reads the material libraries the
/// file names.
pub(crate) fn parse_obj(
    bytes: &[u8],
    name: &str,
    library: LibraryReader<'_>,
) -> Result<Parsed, IoError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        IoError::parse(name, Some(line), "not a text file (invalid UTF-8)")
    })?;
    // Editors on Windows start UTF-8 files with a byte-order mark tobj would take as a word.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let (mut report, file_positions, unreferenced) = prescan(text, name)?;
    let (models, materials) = load_models(text, name, library, &mut report)?;
    let brdfs: Vec<Brdf> = materials.iter().map(material_brdf).collect();
    for material in &materials {
        report.not_kept.extend(material_not_kept(material));
    }

    // tobj numbers each object's vertices in the order faces first use them; putting them back
    // in file order keeps vertex numbers stable across a write and a read.
    let mut file_order: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    for (i, p) in file_positions.iter().enumerate() {
        if !p.is_nan() {
            file_order.entry(weld_key(*p)).or_insert(i as u32);
        }
    }

    let mut parsed = Parsed::default();
    let mut vertex_brdfs: Vec<Option<Brdf>> = Vec::new();
    for (layer, (layer_name, models)) in layers_of(&models).into_iter().enumerate() {
        parsed.layer_names.push(layer_name);
        let base = parsed.soup.positions.len();
        let mut welder = Welder::new(&file_order);
        let per_model: Vec<Vec<u32>> = models
            .iter()
            .map(|m| welder.add(&m.mesh, &mut report))
            .collect();
        let (points, welded_to_global) = welder.finish(base);
        parsed.soup.positions.extend(points.iter().map(|(p, _)| *p));
        vertex_brdfs.resize(parsed.soup.positions.len(), None);
        let mut colours: Vec<Option<[f32; 3]>> = vec![None; base];
        colours.extend(points.iter().map(|(_, c)| *c));
        for (model, local_to_welded) in models.iter().zip(per_model) {
            let brdf = model.mesh.material_id.and_then(|m| brdfs.get(m).copied());
            for face in model_faces(model, &local_to_welded, name)? {
                let face = face.map(|v| welded_to_global[v as usize]);
                for v in face {
                    // A vertex colour is the diffuse albedo; the material gives the rest.
                    let coloured = colours[v as usize].map(|diffuse| Brdf {
                        diffuse,
                        ..brdf.unwrap_or(Brdf::CLAY)
                    });
                    vertex_brdfs[v as usize] = vertex_brdfs[v as usize].or(coloured.or(brdf));
                }
                parsed.soup.faces.push(face);
                parsed.soup.face_layers.push(layer as LayerId);
            }
        }
    }
    if vertex_brdfs.iter().any(Option::is_some) {
        parsed.brdfs = Some(
            vertex_brdfs
                .into_iter()
                .map(|b| b.unwrap_or(Brdf::CLAY))
                .collect(),
        );
    }
    parsed.report = report;
    parsed.unreferenced = unreferenced;
    Ok(parsed)
}

/// The file's models grouped into layers by name, in order of first appearance; models with
/// no triangle are left out. tobj starts a new model at every `usemtl` that changes the
/// material, under the same name: those are one surface.
fn layers_of(models: &[tobj::Model]) -> Vec<(String, Vec<&tobj::Model>)> {
    let mut layers: Vec<(String, Vec<&tobj::Model>)> = Vec::new();
    for model in models.iter().filter(|m| m.mesh.indices.len() >= 3) {
        let name = if model.name.is_empty() || model.name == "unnamed_object" {
            format!("layer{}", layers.len())
        } else {
            model.name.clone()
        };
        let named = (!model.name.is_empty() && model.name != "unnamed_object")
            .then(|| layers.iter().position(|(n, _)| *n == model.name))
            .flatten();
        match named {
            Some(layer) => layers[layer].1.push(model),
            None => layers.push((name, vec![model])),
        }
    }
    layers
}

/// The file's objects through tobj, triangulated (points and lines ignored), and the materials
/// of the libraries it names; an error names the line tobj stopped at. A library that cannot
/// be read is a note, not an error: the mesh is still whole.
fn load_models(
    text: &str,
    name: &str,
    library: LibraryReader<'_>,
    report: &mut ImportReport,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>), IoError> {
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
    let notes = RefCell::new(Vec::new());
    let read_library = |path: &std::path::Path| {
        let shown = crate::files::escape(&path.to_string_lossy()).into_owned();
        let bytes = library(&path.to_string_lossy()).map_err(|why| {
            notes
                .borrow_mut()
                .push(format!("material library `{shown}` not read: {why}"));
            tobj::LoadError::OpenFileFailed
        })?;
        tobj::load_mtl_buf(&mut io::BufReader::new(bytes.as_slice())).inspect_err(|e| {
            notes
                .borrow_mut()
                .push(format!("material library `{shown}` not read: {e}"));
        })
    };
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, read_library)
        .map_err(|e| IoError::parse(name, Some(reader.lines.max(1)), format!("{e}")))?;
    report.notes.extend(notes.into_inner());
    // A library that failed leaves no materials, which tobj reports as an error of its own.
    Ok((models, materials.unwrap_or_default()))
}

/// A welded point and its colour, where the file gives one.
type ColouredPoint = (Vec3, Option<[f32; 3]>);

/// Welds a layer's points by exact bit pattern (+0 and −0 are one point; NaN never welds),
/// numbering them in file order (`file_order`: each point's first line).
struct Welder<'a> {
    file_order: &'a FxHashMap<[u32; 3], u32>,
    ids: FxHashMap<[u32; 3], u32>,
    /// Each welded point with its place in the file (points not found there after those that are).
    points: Vec<(u64, Vec3)>,
    /// Each welded point's colour (`v x y z r g b`), linear, where the file gives one.
    colours: Vec<Option<[f32; 3]>>,
    unmatched: u64,
}

impl<'a> Welder<'a> {
    fn new(file_order: &'a FxHashMap<[u32; 3], u32>) -> Welder<'a> {
        Welder {
            file_order,
            ids: FxHashMap::default(),
            points: Vec::new(),
            colours: Vec::new(),
            unmatched: 1 << 32,
        }
    }

    /// Welds one tobj model's points; returns each one's welded id.
    fn add(&mut self, mesh: &tobj::Mesh, report: &mut ImportReport) -> Vec<u32> {
        let mut local_to_welded = Vec::with_capacity(mesh.positions.len() / 3);
        let mut colours = mesh.vertex_color.chunks_exact(3);
        for p in mesh.positions.chunks_exact(3) {
            let p = Vec3::new(p[0], p[1], p[2]);
            // Colours are sRGB, as every tool that writes them means them.
            let colour = colours
                .next()
                .map(|c| [c[0], c[1], c[2]].map(|c| srgb_to_linear(c.clamp(0.0, 1.0))));
            let key = (!p.is_nan()).then(|| weld_key(p));
            if let Some(&id) = key.and_then(|k| self.ids.get(&k)) {
                report.welded_vertices += 1;
                local_to_welded.push(id);
                continue;
            }
            self.unmatched += 1;
            let order = key
                .and_then(|k| self.file_order.get(&k))
                .map_or(self.unmatched, |&o| o as u64);
            self.points.push((order, p));
            self.colours.push(colour);
            let id = (self.points.len() - 1) as u32;
            if let Some(k) = key {
                self.ids.insert(k, id);
            }
            local_to_welded.push(id);
        }
        local_to_welded
    }

    /// The welded points in file order with their colours, and each welded id's number in the
    /// soup, the points numbered from `base`.
    fn finish(self, base: usize) -> (Vec<ColouredPoint>, Vec<u32>) {
        let mut by_order: Vec<u32> = (0..self.points.len() as u32).collect();
        by_order.sort_by_key(|&id| self.points[id as usize].0);
        let mut welded_to_global = vec![0u32; self.points.len()];
        let mut points = Vec::with_capacity(self.points.len());
        for &id in &by_order {
            welded_to_global[id as usize] = (base + points.len()) as u32;
            points.push((self.points[id as usize].1, self.colours[id as usize]));
        }
        (points, welded_to_global)
    }
}

/// An object's triangles in welded ids; an index out of range is an error naming the object
/// and triangle. Triangles that repeat a point are kept for the repair (or the strict refusal).
fn model_faces(
    model: &tobj::Model,
    local_to_welded: &[u32],
    name: &str,
) -> Result<Vec<[u32; 3]>, IoError> {
    let mut faces = Vec::with_capacity(model.mesh.indices.len() / 3);
    for (k, tri) in model.mesh.indices.chunks_exact(3).enumerate() {
        let face = [tri[0], tri[1], tri[2]]
            .map(|i| local_to_welded.get(i as usize).copied().unwrap_or(INVALID));
        if face.contains(&INVALID) {
            return Err(IoError::parse(
                name,
                None,
                format!(
                    "object `{}`: triangle {k} has a vertex index out of range",
                    crate::files::escape(&model.name)
                ),
            ));
        }
        faces.push(face);
    }
    Ok(faces)
}

/// What the pre-scan counts that a mesh does not keep.
#[derive(Default)]
struct Dropped {
    texture_coordinates: usize,
    normals: usize,
    lines: usize,
    points: usize,
}

impl Dropped {
    fn items(&self) -> Vec<String> {
        counted(&[
            (self.texture_coordinates, "texture coordinates (`vt`)"),
            (self.normals, "normals (`vn`; recomputed)"),
            (self.lines, "line elements (`l`)"),
            (self.points, "point elements (`p`)"),
        ])
    }
}

/// Checks every `v` and `f` line for what tobj would reject without a line number or accept
/// wrongly: unparsable or missing numbers, index 0, indices past the vertices defined so far.
/// Returns the report so far, the file's points, and how many of them no face uses.
fn prescan(text: &str, name: &str) -> Result<(ImportReport, Vec<Vec3>, usize), IoError> {
    let mut report = ImportReport::default();
    let mut dropped = Dropped::default();
    let mut file_positions = Vec::new();
    let mut used: Vec<bool> = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let number = number + 1;
        let error = |message: String| IoError::parse(name, Some(number), message);
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let p = vertex_line(words).map_err(error)?;
                if !p.is_finite() {
                    report.non_finite_vertices += 1;
                    report.first_non_finite_line.get_or_insert(number);
                } else if p.abs().max_element() > MAX_COORDINATE {
                    return Err(error(format!(
                        "vertex coordinate beyond the supported range ±{MAX_COORDINATE:e}"
                    )));
                }
                file_positions.push(p);
                used.push(false);
            }
            Some("vt") => dropped.texture_coordinates += 1,
            Some("vn") => dropped.normals += 1,
            Some("l") => dropped.lines += 1,
            Some("p") => dropped.points += 1,
            Some("f") => {
                let defined = [
                    file_positions.len(),
                    dropped.texture_coordinates,
                    dropped.normals,
                ];
                for v in face_line(words, defined).map_err(error)? {
                    used[v] = true;
                }
            }
            _ => {}
        }
    }
    report.not_kept = dropped.items();
    let unused = used.iter().filter(|&&u| !u).count();
    Ok((report, file_positions, unused))
}

/// The point of a `v` line (after the `v`); colours or a weight after it are tobj's business.
fn vertex_line<'a>(mut words: impl Iterator<Item = &'a str>) -> Result<Vec3, String> {
    let mut coordinates = [0f32; 3];
    for (axis, slot) in coordinates.iter_mut().enumerate() {
        match words.next().map(str::parse::<f32>) {
            Some(Ok(value)) => *slot = value,
            Some(Err(_)) => return Err(format!("vertex coordinate {axis} is not a number")),
            None => return Err("vertex needs three coordinates".into()),
        }
    }
    Ok(Vec3::from_array(coordinates))
}

/// Checks an `f` line's corners (after the `f`) against the `defined` positions, texture
/// coordinates and normals so far; returns the positions it uses (from 0).
fn face_line<'a>(
    words: impl Iterator<Item = &'a str>,
    defined: [usize; 3],
) -> Result<Vec<usize>, String> {
    let mut corners = Vec::new();
    for word in words {
        let fields = ["vertex", "texture", "normal"].into_iter().zip(defined);
        for (field, (what, defined)) in word.split('/').zip(fields) {
            if field.is_empty() && what != "vertex" {
                continue;
            }
            let Ok(index) = field.parse::<i64>() else {
                return Err(format!("face {what} index `{field}` is not an integer"));
            };
            let in_range = if index > 0 {
                index as u64 <= defined as u64
            } else {
                index != 0 && index.unsigned_abs() <= defined as u64
            };
            if !in_range {
                return Err(format!(
                    "face {what} index {index} is out of range ({defined} defined so far)"
                ));
            }
            if what == "vertex" {
                let from_end = index < 0;
                corners.push(if from_end {
                    defined - index.unsigned_abs() as usize
                } else {
                    index as usize - 1
                });
            }
        }
        if word.split('/').count() > 3 {
            return Err(format!("face corner `{word}` has more than three indices"));
        }
    }
    if corners.len() < 3 {
        return Err(format!(
            "face has {} corners; at least 3 are needed",
            corners.len()
        ));
    }
    Ok(corners)
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
