//! From what a reader parsed to a mesh: repaired by default ([`crate::mesh::repair`]), or
//! refused with `strict`, with a report of what was repaired and of what the file held that a
//! slayer mesh does not keep (texture coordinates, normals, properties of other tools).

use serde::Serialize;

use super::IoError;
use crate::mesh::{Brdf, LayerId, Mesh, Repairs, Soup, VertexFlags, repair, without_unreferenced};

/// How an import treats a file that reads fine but is not a clean manifold mesh.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ImportOptions {
    /// Refuse such a file, naming the first broken element, instead of repairing it (unused
    /// vertices are still dropped: they change nothing).
    pub strict: bool,
}

/// What an import did and found besides the mesh.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ImportReport {
    pub repairs: Repairs,
    /// What the file held that the mesh does not keep, one item each: `120 texture coordinates`.
    pub not_kept: Vec<String>,
    /// Anything else worth a line: a material library that could not be read.
    pub notes: Vec<String>,
    /// Vertices at the same position within a layer, merged into one (OBJ).
    pub welded_vertices: usize,
    /// Vertices with a non-finite coordinate, and the first such line where the format has
    /// lines; [`read_mesh`](super::read_mesh) refuses them, `check` reports them.
    pub non_finite_vertices: usize,
    pub first_non_finite_line: Option<usize>,
    /// The layers a slayer PLY marks as fuse (their proximity policy; `docs/topology.md`),
    /// ascending, each an existing layer.
    pub fuse_layers: Vec<LayerId>,
}

impl ImportReport {
    /// The lines a command prints after reading a file: what was repaired, what was not kept,
    /// the notes. Nothing for a clean file.
    pub fn lines(&self) -> Vec<String> {
        let mut lines = Vec::new();
        if self.repairs.any() {
            lines.push(format!("repaired: {}", self.repairs));
        }
        if !self.not_kept.is_empty() {
            lines.push(format!("not kept: {}", self.not_kept.join(", ")));
        }
        lines.extend(self.notes.iter().cloned());
        lines
    }
}

/// `120 texture coordinates`-style items of the counts that are not zero.
pub(super) fn counted(items: &[(usize, &str)]) -> Vec<String> {
    items
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, what)| format!("{n} {what}"))
        .collect()
}

/// What a reader got from a file: the soup and, per soup vertex, the attributes the file gave.
#[derive(Debug, Default)]
pub(crate) struct Parsed {
    pub soup: Soup,
    pub layer_names: Vec<String>,
    pub brdfs: Option<Vec<Brdf>>,
    pub flags: Option<Vec<VertexFlags>>,
    pub report: ImportReport,
    /// Vertices the reader already left out because no face uses them (an OBJ's), counted
    /// with the repair's.
    pub unreferenced: usize,
}

/// Builds the mesh of `parsed`, repairing it unless `options` say strict.
pub(crate) fn build(
    parsed: Parsed,
    options: &ImportOptions,
    name: &str,
) -> Result<(Mesh, ImportReport), IoError> {
    let Parsed {
        soup,
        layer_names,
        brdfs,
        flags,
        mut report,
        unreferenced,
    } = parsed;
    if soup.faces.is_empty() {
        return Err(IoError::parse(name, None, "no faces"));
    }
    let unchecked = soup.positions.clone();
    let repaired = if options.strict {
        without_unreferenced(soup)
    } else {
        repair(soup)
    }
    .map_err(|e| IoError::building(name, e, &unchecked))?;
    report.repairs = repaired.repairs;
    report.repairs.unreferenced_vertices += unreferenced;
    let soup = repaired.soup;
    if soup.faces.is_empty() {
        let why = format!("no faces left after the repair ({})", report.repairs);
        return Err(IoError::parse(name, None, why));
    }
    let positions = soup.positions.clone();
    let mut mesh = Mesh::new(soup.positions, soup.faces, soup.face_layers, layer_names)
        .map_err(|e| IoError::building(name, e, &positions))?;
    report
        .fuse_layers
        .retain(|&l| (l as usize) < mesh.layer_count());
    report.fuse_layers.sort_unstable();
    report.fuse_layers.dedup();
    let follow = |v: &u32| *v as usize;
    if let Some(brdfs) = brdfs {
        let per_vertex = repaired.source.iter().map(|v| brdfs[follow(v)]).collect();
        mesh.set_brdfs(per_vertex)
            .map_err(|e| IoError::building(name, e, &positions))?;
    }
    if let Some(flags) = flags {
        for (flag, v) in mesh.flags_mut().iter_mut().zip(&repaired.source) {
            *flag |= flags[follow(v)] & VertexFlags::PERSISTENT;
        }
    }
    Ok((mesh, report))
}
