//! `slayer check`: what a mesh file holds and everything wrong with it.

use serde::Serialize;

use crate::collide::{find_intersections, smallest_layer_gap};
use crate::grid::SpatialHash;
use crate::io::ImportReport;
use crate::mesh::{ClosedComponent, ComponentShape, Mesh};
use crate::remesh::MIN_CLOSED_FACES;

/// A closed component whose volume changed by more than this share from the `--against` file
/// is a defect. Remeshing changes one by at most `remesh::VOLUME_TOLERANCE` (2 %) a pass, so a
/// remesh or two stay below; the shapes issue 22 found destroyed had lost 7 % to 99 %.
pub const VOLUME_CHANGE_DEFECT: f64 = 0.05;

/// How far, in mean edges, `check` looks for the smallest gap between layers.
pub const GAP_REACH_EDGES: f64 = 3.0;

/// Figures and defects of one mesh. Field names are part of the `--json` interface.
#[derive(Debug, Clone, Serialize)]
pub struct CheckReport {
    pub file: String,
    pub vertices: usize,
    pub faces: usize,
    pub layers: usize,
    pub layer_names: Vec<String>,
    pub faces_per_layer: Vec<usize>,
    pub components: usize,
    pub components_per_layer: Vec<usize>,
    /// The layers whose proximity policy is fuse, as the file says (a slayer PLY's header, a
    /// session's layer settings); the others collide.
    pub fuse_layers: Vec<crate::mesh::LayerId>,
    /// Each component's topology: layer, faces, boundary loops (0: closed), Euler
    /// characteristic and genus.
    pub component_shapes: Vec<crate::mesh::ComponentShape>,
    pub mean_edge_length: f64,
    pub edge_length_cv: f64,
    pub min_edge_length: f64,
    pub max_edge_length: f64,
    pub valid: bool,
    pub validation_error: Option<String>,
    pub non_finite: usize,
    pub intersections: usize,
    pub intersections_between_layers: usize,
    pub intersections_within_layers: usize,
    /// Faces folded onto a neighbour they share a vertex or an edge with (in `intersections`).
    pub folded_neighbours: usize,
    pub intersection_examples: Vec<[u32; 2]>,
    /// The smallest distance from a vertex to another layer's faces, where one is within
    /// [`GAP_REACH_EDGES`] mean edges (the engine keeps it at least the collision distance).
    pub smallest_layer_gap: Option<f64>,
    /// Closed components (no boundary edge) and the face count of the smallest.
    pub closed_components: usize,
    pub smallest_closed_faces: Option<usize>,
    /// With `--against ORIGINAL`: each closed component of the original and its volume here.
    pub volume_changes: Option<Vec<VolumeChange>>,
    /// With `--against ORIGINAL`: faces on the same three vertices in both whose normal now
    /// points against the original's (turned over: a fold the intersection test cannot see).
    pub turned_over_faces: Option<usize>,
    /// The vertex grid the engine would build (cell = mean edge length).
    pub grid: Option<GridFigures>,
    /// What reading the file repaired (all zero for a clean file or a session).
    pub repairs: crate::mesh::Repairs,
    /// What the file held that the mesh does not keep (texture coordinates, normals, ...).
    pub not_kept: Vec<String>,
    /// Other notes from reading the file (a material library not read).
    pub import_notes: Vec<String>,
    /// One line per defect; empty when the mesh is clean.
    pub defects: Vec<String>,
    /// The content digest ([`Mesh::digest`]): equal for the same mesh however it was stored.
    pub digest: String,
}

impl CheckReport {
    pub fn is_clean(&self) -> bool {
        self.defects.is_empty()
    }

    /// Compares the closed components' volumes with those of `original` (the file this one
    /// was made from), adding a defect for each that changed by more than
    /// [`VOLUME_CHANGE_DEFECT`] or is gone.
    pub fn compare_with(&mut self, mesh: &Mesh, original: &Mesh) {
        let changes = volume_changes(&mesh.closed_components(), &original.closed_components());
        for c in &changes {
            match (c.after, c.change) {
                (None, _) => self.defects.push(format!(
                    "closed component {} (layer {}, volume {:.6}) of the original has no closed counterpart",
                    c.component, c.layer, c.before
                )),
                (Some(after), Some(change)) if change.abs() > VOLUME_CHANGE_DEFECT => {
                    self.defects.push(format!(
                        "closed component {} (layer {}) changed volume by {:+.1} % ({:.6} -> {after:.6}); more than {} % is a lost shape",
                        c.component,
                        c.layer,
                        100.0 * change,
                        c.before,
                        100.0 * VOLUME_CHANGE_DEFECT
                    ))
                }
                _ => {}
            }
        }
        self.volume_changes = Some(changes);
        self.turned_over_faces = Some(turned_over_faces(mesh, original));
    }
}

/// Faces on the same three vertices in `mesh` and `original` whose normals point apart.
pub fn turned_over_faces(mesh: &Mesh, original: &Mesh) -> usize {
    let shared = mesh.face_count().min(original.face_count());
    (0..shared)
        .filter(|&f| {
            let face = mesh.faces()[f];
            face[0] != crate::mesh::INVALID
                && face == original.faces()[f]
                && mesh.face_normal(f).dot(original.face_normal(f)) < 0.0
        })
        .count()
}

/// One closed component of an original mesh and the component of the same layer nearest to
/// it in the mesh checked.
#[derive(Debug, Clone, Serialize)]
pub struct VolumeChange {
    /// Its number among the original's closed components.
    pub component: usize,
    pub layer: u32,
    pub before: f64,
    /// `None` when the mesh checked has no closed component left to match it.
    pub after: Option<f64>,
    /// `(after - before) / |before|`.
    pub change: Option<f64>,
}

/// Matches each original closed component with the nearest unmatched one of its layer (by
/// centroid) and compares volumes.
fn volume_changes(now: &[ClosedComponent], original: &[ClosedComponent]) -> Vec<VolumeChange> {
    let mut taken = vec![false; now.len()];
    original
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let nearest = now
                .iter()
                .enumerate()
                .filter(|(j, c)| !taken[*j] && c.layer == o.layer)
                .min_by(|(_, a), (_, b)| {
                    let (da, db) = (
                        a.centroid.distance(o.centroid),
                        b.centroid.distance(o.centroid),
                    );
                    da.total_cmp(&db)
                })
                .map(|(j, c)| (j, c.volume));
            if let Some((j, _)) = nearest {
                taken[j] = true;
            }
            let after = nearest.map(|(_, v)| v);
            VolumeChange {
                component: i,
                layer: o.layer,
                before: o.volume,
                after,
                change: after.map(|a| (a - o.volume) / o.volume.abs().max(f64::MIN_POSITIVE)),
            }
        })
        .collect()
}

/// The spatial hash over the mesh's vertices, as the brush pipeline builds it per stroke.
#[derive(Debug, Clone, Serialize)]
pub struct GridFigures {
    pub cell_size: f64,
    pub occupied_cells: usize,
    pub max_vertices_per_cell: usize,
    pub build_ms: f64,
    pub memory_bytes: usize,
}

/// Measures a loaded mesh. `progress` is told which step is running.
pub fn check_mesh(
    mesh: &Mesh,
    notes: &ImportReport,
    file: &str,
    mut progress: impl FnMut(&str),
) -> CheckReport {
    progress("measuring edges");
    let stats = mesh.edge_length_stats();
    progress("labelling components");
    let components = mesh.components();
    progress("validating");
    let validation = mesh.validate();
    let non_finite = notes
        .non_finite_vertices
        .max(mesh.positions().iter().filter(|p| !p.is_finite()).count());
    progress("building the spatial hash");
    let grid = (non_finite == 0)
        .then(|| grid_figures(mesh, stats.mean as f32))
        .flatten();
    progress("testing triangle pairs for intersections");
    let intersections = find_intersections(mesh);
    let reach = (GAP_REACH_EDGES * stats.mean) as f32;
    let smallest_layer_gap = smallest_layer_gap(mesh, reach)
        .ok()
        .flatten()
        .map(f64::from);
    let closed = mesh.closed_components();
    let smallest_closed_faces = closed.iter().map(|c| c.faces).min();

    let faces = mesh.live_face_count();
    let found = Found {
        faces,
        non_finite,
        first_non_finite_line: notes.first_non_finite_line,
        validation: &validation,
        intersections: &intersections,
        closed: &closed,
    };
    let defects = found.defects();
    CheckReport {
        file: file.to_string(),
        vertices: mesh.live_vertex_count(),
        faces,
        layers: mesh.layer_count(),
        layer_names: mesh.layer_names().to_vec(),
        faces_per_layer: mesh.faces_per_layer(),
        components: components.count(),
        components_per_layer: components.per_layer(mesh.layer_count()),
        fuse_layers: notes.fuse_layers.clone(),
        component_shapes: mesh.component_shapes(),
        mean_edge_length: stats.mean,
        edge_length_cv: stats.coefficient_of_variation(),
        min_edge_length: stats.min,
        max_edge_length: stats.max,
        valid: validation.is_ok(),
        validation_error: validation.err().map(|e| e.to_string()),
        non_finite,
        intersections: intersections.total(),
        intersections_between_layers: intersections.between_layers,
        intersections_within_layers: intersections.within_layers,
        folded_neighbours: intersections.folded_neighbours,
        intersection_examples: intersections
            .examples
            .iter()
            .map(|p| [p.face_a, p.face_b])
            .collect(),
        smallest_layer_gap,
        closed_components: closed.len(),
        smallest_closed_faces,
        volume_changes: None,
        turned_over_faces: None,
        grid,
        repairs: notes.repairs,
        not_kept: notes.not_kept.clone(),
        import_notes: notes.notes.clone(),
        defects,
        digest: mesh.digest(),
    }
}

/// The figures of the grid the engine would build (cell = `cell`), timed; `None` when it
/// cannot be built.
fn grid_figures(mesh: &Mesh, cell: f32) -> Option<GridFigures> {
    let started = std::time::Instant::now();
    let grid = SpatialHash::build(mesh, cell).ok()?;
    Some(GridFigures {
        cell_size: grid.cell_size() as f64,
        occupied_cells: grid.occupied_cells(),
        max_vertices_per_cell: grid.max_cell_occupancy(),
        build_ms: started.elapsed().as_secs_f64() * 1e3,
        memory_bytes: grid.memory_bytes(),
    })
}

/// What `check_mesh` measured that can make a defect.
struct Found<'a> {
    faces: usize,
    non_finite: usize,
    first_non_finite_line: Option<usize>,
    validation: &'a Result<(), crate::mesh::MeshError>,
    intersections: &'a crate::collide::IntersectionReport,
    closed: &'a [ClosedComponent],
}

impl Found<'_> {
    /// One line per defect.
    fn defects(&self) -> Vec<String> {
        let mut defects = Vec::new();
        if self.faces == 0 {
            defects.push("the mesh has no faces".to_string());
        }
        if self.non_finite > 0 {
            let at = self
                .first_non_finite_line
                .map(|l| format!(" (first at line {l})"))
                .unwrap_or_default();
            defects.push(format!(
                "{} vertices have non-finite coordinates{at}",
                self.non_finite
            ));
        }
        if let Err(e) = self.validation {
            defects.push(format!("invalid mesh: {e}"));
        }
        let x = self.intersections;
        if x.total() > 0 {
            let examples: Vec<[u32; 2]> = x
                .examples
                .iter()
                .map(|p| [p.face_a, p.face_b])
                .take(3)
                .collect();
            defects.push(format!(
                "{} intersecting triangle pairs ({} between layers, {} within a layer, {} folded onto a neighbour), e.g. faces {examples:?}",
                x.total(),
                x.between_layers,
                x.within_layers,
                x.folded_neighbours,
            ));
        }
        for (i, c) in self.closed.iter().enumerate() {
            if c.faces < MIN_CLOSED_FACES {
                defects.push(format!(
                    "closed component {i} (layer {}) has only {} faces, fewer than {MIN_CLOSED_FACES}: a collapsed shape",
                    c.layer, c.faces
                ));
            }
        }
        defects
    }
}

impl CheckReport {
    /// One line on a layer's components: how many are closed and their genera, how many are
    /// open and their boundary loops.
    fn layer_topology(&self, layer: u32) -> String {
        let shapes: Vec<_> = (self.component_shapes.iter())
            .filter(|s| s.layer == layer)
            .collect();
        let (closed, open): (Vec<&ComponentShape>, Vec<_>) =
            shapes.iter().partition(|s| s.is_closed());
        let genera = match closed.len() {
            0 => String::new(),
            1..=6 => {
                let list: Vec<String> = closed.iter().map(|s| s.genus.to_string()).collect();
                format!(" (genus {})", list.join(", "))
            }
            _ => format!(
                " (genus {} in all)",
                closed.iter().map(|s| s.genus).sum::<i64>()
            ),
        };
        let loops: usize = open.iter().map(|s| s.boundary_loops).sum();
        format!(
            "       {} closed{genera}, {} open ({loops} boundary loops)",
            closed.len(),
            open.len()
        )
    }
}

impl std::fmt::Display for CheckReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{}", self.file)?;
        if self.repairs.any() {
            writeln!(f, "  repaired          {}", self.repairs)?;
        }
        if !self.not_kept.is_empty() {
            writeln!(f, "  not kept          {}", self.not_kept.join(", "))?;
        }
        for note in &self.import_notes {
            writeln!(f, "  note              {note}")?;
        }
        writeln!(f, "  vertices          {}", self.vertices)?;
        writeln!(f, "  faces             {}", self.faces)?;
        writeln!(f, "  layers            {}", self.layers)?;
        for (i, name) in self.layer_names.iter().enumerate() {
            // Names come from the file: escaped, so that they cannot drive the terminal.
            let name = crate::files::escape(name);
            let fuses = self.fuse_layers.contains(&(i as u32));
            writeln!(
                f,
                "    {i}: {name:<14} {:>9} faces  {:>5} components  {}",
                self.faces_per_layer.get(i).copied().unwrap_or(0),
                self.components_per_layer.get(i).copied().unwrap_or(0),
                if fuses { "fuse" } else { "collide" }
            )?;
            writeln!(f, "{}", self.layer_topology(i as u32))?;
        }
        writeln!(f, "  components        {}", self.components)?;
        writeln!(
            f,
            "  mean edge length  {:.6}  (cv {:.3}, min {:.6}, max {:.6})",
            self.mean_edge_length, self.edge_length_cv, self.min_edge_length, self.max_edge_length
        )?;
        writeln!(
            f,
            "  valid             {}",
            if self.valid { "yes" } else { "no" }
        )?;
        writeln!(f, "  non-finite        {}", self.non_finite)?;
        writeln!(
            f,
            "  intersections     {}  ({} between layers, {} within a layer, {} folded onto a neighbour)",
            self.intersections,
            self.intersections_between_layers,
            self.intersections_within_layers,
            self.folded_neighbours
        )?;
        match self.smallest_layer_gap {
            Some(gap) => writeln!(
                f,
                "  layer gap         {gap:.6}  ({:.2} mean edges), the smallest vertex-to-other-layer distance",
                gap / self.mean_edge_length
            )?,
            None if self.layers > 1 => writeln!(
                f,
                "  layer gap         no layer within {GAP_REACH_EDGES} mean edges of another"
            )?,
            None => {}
        }
        if let Some(smallest) = self.smallest_closed_faces {
            writeln!(
                f,
                "  closed            {} components, the smallest {smallest} faces",
                self.closed_components
            )?;
        }
        if let Some(turned) = self.turned_over_faces {
            writeln!(f, "  turned over       {turned} faces against the original")?;
        }
        for c in self.volume_changes.iter().flatten() {
            match (c.after, c.change) {
                (Some(after), Some(change)) => writeln!(
                    f,
                    "    volume of closed component {} (layer {}): {:.6} -> {after:.6} ({:+.2} %)",
                    c.component,
                    c.layer,
                    c.before,
                    100.0 * change
                )?,
                _ => writeln!(
                    f,
                    "    volume of closed component {} (layer {}): {:.6} -> gone",
                    c.component, c.layer, c.before
                )?,
            }
        }
        if let Some(g) = &self.grid {
            writeln!(
                f,
                "  spatial hash      {} cells, at most {} vertices a cell, {:.1} MiB, built in {:.1} ms",
                g.occupied_cells,
                g.max_vertices_per_cell,
                g.memory_bytes as f64 / (1024.0 * 1024.0),
                g.build_ms
            )?;
        }
        writeln!(f, "  digest            {}", self.digest)?;
        if self.defects.is_empty() {
            write!(f, "  ok: no defects")
        } else {
            for d in &self.defects {
                writeln!(f, "  defect: {d}")?;
            }
            write!(f, "  {} defect(s)", self.defects.len())
        }
    }
}
