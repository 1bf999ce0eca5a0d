//! The faces around one step (its [`Region`]), gathered through the grid and filed in a local
//! face grid, with the per-thread scratch the searches over it use: the ground both phases of
//! the collision response stand on (the proximity clamp, `super::response`; the exact
//! backstop, `super::backstop`).

use glam::Vec3;
use rayon::prelude::*;

use super::rings::RingCache;
use super::sheet::{FaceSlope, Sheet};
use super::state::StrokeState;
use super::{LocalFaceGrid, Stamps, SweptTriangle};
use crate::geom::{Aabb, largest_move};
use crate::grow::grow_to;
use crate::mesh::{INVALID, Mesh, MeshVersion};

/// A step's moves: the selection, each selected vertex's target, and per vertex its index in
/// the selection (`INVALID` for the others).
pub type StepMoves<'a> = (&'a [(u32, f32)], &'a [Vec3], &'a [u32]);

/// Per-thread scratch: the faces a query has met, a ring, a candidate list.
#[derive(Default)]
pub struct Scratch {
    seen: Stamps,
    pub(super) ring: Vec<u32>,
    pub(super) nearby: Vec<u32>,
    cells: Vec<u32>,
}

/// Maps `f` over `items`, in parallel or not, with per-thread scratch.
pub(super) fn map_with_scratch<T: Send, I: Sync>(
    parallel: bool,
    items: &[I],
    f: impl Fn(&mut Scratch, &I) -> T + Sync + Send,
) -> Vec<T> {
    if parallel {
        items
            .par_iter()
            .map_init(Scratch::default, |s, item| f(s, item))
            .collect()
    } else {
        let mut scratch = Scratch::default();
        items.iter().map(|item| f(&mut scratch, item)).collect()
    }
}

/// The faces around one step: everything that could come within the collision distance of a
/// moving vertex, or cross a moving face. Kept in the pipeline between steps so its buffers are
/// reused.
#[derive(Default)]
pub struct Region {
    pub(super) faces: Vec<u32>,
    /// Per local face: box of its old and target positions.
    pub(super) boxes: Vec<Aabb>,
    /// Per local face: where it starts and how its corners move (filed by it, not its box).
    swept: Vec<SweptTriangle>,
    grid: LocalFaceGrid,
    use_grid: bool,
    /// The local grid's cell side (none without a global grid), and which faces are filed in
    /// it yet.
    cell: Option<f32>,
    filed: Filing,
    vertices: Vec<u32>,
    /// Per local face: its layer (read where a search skips one).
    local_layers: Vec<u32>,
    /// Mesh faces already in `faces`, and their index there.
    gathered: Stamps,
    local_index: Vec<u32>,
    /// The box of the step's moves (starts and targets), and the box whose vertices were
    /// gathered (filed in the grid in a cell that overlaps it).
    pub(super) bounds: Aabb,
    reach: Aabb,
    /// Gathered for the step under way ([`Region::forget`] clears it between steps).
    pub(super) ready: bool,
    /// The layers of the region's faces, ascending.
    layers: Vec<u32>,
    /// The layers of the step's selection, ascending: those whose searches may be skipped.
    moving_layers: Vec<u32>,
    /// Per layer id: the region's faces of that layer as a sheet where the mesh is now, if
    /// they are one (`super::sheet`); `None` once a vertex moved since it was found.
    sheets: Option<Vec<Option<Sheet>>>,
    /// Per local face, when the region is one layer and a sheet not clear as a whole: how it
    /// stands to the sheet's axis (`super::sheet::clear_around`).
    pub(super) slopes: Vec<FaceSlope>,
    /// The first look this step found no sheet.
    no_sheet_this_step: bool,
    /// Mesh faces met already, for the phases that list each face once.
    face_marks: Stamps,
    /// Mesh faces filed already by [`Region::file_faces_near`].
    near_marks: Stamps,
    /// The moving vertices' exclusion rings, kept from step to step.
    pub(super) rings: RingCache,
    /// The faces the last Jacobi pass changed, filed apart ([`Region::file_changed`]).
    changed: ChangedFaces,
    /// Moving vertices whose own neighbourhood cleared them of a search this step
    /// (`super::sheet::clear_around`).
    pub(super) cleared_vertices: usize,
    /// Where the mesh stood, and whether the listing went through a grid, when a step that
    /// gathered this region ended ([`Region::step_ended`]). While the mesh stands there and
    /// lists the same way, the vertices and faces listed are still those around the reach:
    /// that step moved only its selection, which the listing holds; no vertex outside it
    /// moved, so none entered the reach, and the faces are as they were.
    whole_at: Option<(MeshVersion, bool)>,
    /// The last gathering kept the vertices and faces it found before.
    pub(super) kept_last: bool,
}

/// Which of a region's faces its local grid holds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
enum Filing {
    #[default]
    None,
    /// Only those a few searched vertices can meet ([`Region::file_faces_near`]).
    Near,
    All,
}

/// The local faces a Jacobi pass of the clamp changed (around the vertices it pulled back),
/// in a grid of their own: the next pass tests most vertices only against them, and a query
/// through the whole region's grid read ~190 entries to find them among ~30 overlapping
/// boxes (a grab over a 50K-face sphere), nearly as much as the first pass.
#[derive(Default)]
struct ChangedFaces {
    /// Local face indices, ascending.
    faces: Vec<u32>,
    boxes: Vec<Aabb>,
    swept: Vec<SweptTriangle>,
    grid: LocalFaceGrid,
    /// Filed for the pass under way.
    filed: bool,
}

impl Region {
    /// Sizes the per-face arrays for `mesh` ahead of the first step (set-up, not a stroke's).
    pub fn size_for(&mut self, mesh: &Mesh) {
        self.gathered.size_for(mesh.face_count());
        self.face_marks.size_for(mesh.face_count());
        self.near_marks.size_for(mesh.face_count());
        grow_to(&mut self.local_index, mesh.face_count(), 0);
        self.rings.size_for(mesh.vertex_count());
    }

    /// Collects the faces around the step's moves, ready for searching (public so that
    /// `tests/gpu_parity/` can check the GPU proximity mirror against
    /// [`pull_back`](super::pull_back)).
    pub fn gather(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        selection: &[(u32, f32)],
        targets: &[Vec3],
        target_of: &[u32],
    ) {
        self.gather_unfiled(state, mesh, selection, targets);
        let before: Vec<Vec3> = selection
            .iter()
            .map(|&(v, _)| mesh.positions()[v as usize])
            .collect();
        self.file_faces(mesh, (selection, targets, target_of), &before);
    }

    /// [`Region::gather`] without filing the faces in the local grid: the searches that need
    /// it call [`Region::file_faces`] first; a step whose every layer is a sheet needs none.
    pub(super) fn gather_unfiled(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        selection: &[(u32, f32)],
        targets: &[Vec3],
    ) {
        let positions = mesh.positions();
        let mut bounds = Aabb::EMPTY;
        for (&(v, _), &q) in selection.iter().zip(targets) {
            bounds = bounds.including(positions[v as usize]).including(q);
        }
        // A face within d of a moving point has a vertex within d + longest edge; a face that
        // crosses a moving face has a vertex within two longest edges of the moving vertex.
        let reach = state.collision_distance + 2.0 * state.max_edge;
        self.bounds = bounds;
        let whole = self.whole_at.take() == Some((mesh.version(), state.grid.is_some()));
        self.kept_last = whole && self.covers_box(&bounds.expanded(reach));
        if !self.kept_last {
            // Room for a next step of the same sample, which moves on about as far again.
            let step = selection
                .iter()
                .zip(targets)
                .map(|(&(v, _), &q)| (q - positions[v as usize]).abs().max_element());
            self.list_around(
                state,
                mesh,
                bounds.expanded(reach + step.fold(0.0, f32::max)),
            );
        }
        // Only a moving vertex's own layer is ever skipped: only those layers are tested.
        let moving = selection
            .iter()
            .map(|&(v, _)| mesh.vertex_layers()[v as usize]);
        layers_among(mesh.layer_count(), moving, &mut self.moving_layers);
        self.sheets = None;
        self.no_sheet_this_step = false;
        self.ready = true;
        self.use_grid = state.grid.is_some();
        self.cell = state.grid.map(|g| LOCAL_CELL_EDGES * g.cell_size());
        self.filed = Filing::None;
        self.changed.filed = false;
    }

    /// The step under way ends with the mesh where it is now: if it gathered this region, a
    /// next step whose reach lies within this one's may keep its listing
    /// ([`Region::gather_unfiled`]).
    pub(super) fn step_ended(&mut self, mesh: &Mesh) {
        self.whole_at = self.ready.then(|| (mesh.version(), self.use_grid));
    }

    /// Lists the vertices filed in a cell that overlaps `region` (or, without a grid, lying in
    /// it) and their faces.
    fn list_around(&mut self, state: &StrokeState<'_>, mesh: &Mesh, region: Aabb) {
        let positions = mesh.positions();
        self.reach = region;
        self.vertices.clear();
        match state.grid {
            Some(grid) => {
                let vertices = &mut self.vertices;
                grid.for_each_in_box(region.min, region.max, |v| vertices.push(v));
            }
            None => self
                .vertices
                .extend((0..mesh.vertex_count() as u32).filter(|&v| {
                    let p = positions[v as usize];
                    mesh.adjacency().vertex_corner[v as usize] != INVALID
                        && p.cmpge(region.min).all()
                        && p.cmple(region.max).all()
                })),
        }
        // Faces of those vertices, each once. Their order does not matter: every result below
        // is a minimum or a sorted set.
        self.gathered.start(mesh.face_count());
        grow_to(&mut self.local_index, mesh.face_count(), 0);
        self.faces.clear();
        for &v in &self.vertices {
            for f in mesh.faces_around(v) {
                if self.gathered.insert(f as usize) {
                    self.local_index[f as usize] = self.faces.len() as u32;
                    self.faces.push(f);
                }
            }
        }
        self.local_layers.clear();
        (self.local_layers).extend(self.faces.iter().map(|&f| mesh.face_layers()[f as usize]));
        let face_layers = self.local_layers.iter().copied();
        layers_among(mesh.layer_count(), face_layers, &mut self.layers);
    }

    /// Boxes the faces (around where each vertex starts the step and, if it moves, its
    /// target; `before` holds the selection's starts) and files them in the local grid, once
    /// per gathering.
    pub(super) fn file_faces(&mut self, mesh: &Mesh, moves: StepMoves<'_>, before: &[Vec3]) {
        if self.filed == Filing::All {
            return;
        }
        // Each face's sweep is its own: worked out on every core (bark files 7,400 faces a
        // step, and this ran on one while the other waited).
        (self.faces.par_iter())
            .with_min_len(SWEEPS_PER_JOB)
            .map(|&f| sweep_of(mesh, f, moves, before))
            .unzip_into_vecs(&mut self.boxes, &mut self.swept);
        if let Some(cell) = self.cell {
            self.grid
                .build_swept(&self.boxes, &self.swept, self.reach, cell);
        }
        self.filed = Filing::All;
    }

    /// Files every face, where [`Region::file_faces_near`] filed only some.
    pub(super) fn file_the_rest(&mut self, mesh: &Mesh, moves: StepMoves<'_>, before: &[Vec3]) {
        if self.filed == Filing::Near {
            self.file_faces(mesh, moves, before);
        }
    }

    /// Files, for the first pass's searches of the selection's vertices at `searched` (slots),
    /// only the faces those can meet: where a few vertices of a ridge's flanks are left to
    /// search in a region of thousands of faces, boxing and filing them all cost more than
    /// the searches. Later searches file the rest ([`Region::file_faces`]).
    ///
    /// A vertex's search meets the faces whose box overlaps the box of its move grown by `d`.
    /// A face's box lies within `max_edge` and the step's longest move (per axis) of each
    /// corner's start, where the global grid files the corner during the step; so the grid's
    /// vertices in the search box grown by those two hold a corner of every such face.
    pub(super) fn file_faces_near(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        moves: StepMoves<'_>,
        (before, searched): (&[Vec3], &[usize]),
    ) {
        let Some(grid) = state.grid.filter(|_| self.use_grid) else {
            return self.file_faces(mesh, moves, before);
        };
        if self.filed != Filing::None {
            return;
        }
        // Past this share of the region's faces per searched vertex, filing them all is as
        // cheap.
        if searched.len() * FACES_NEAR_ONE_SEARCH > self.faces.len() {
            return self.file_faces(mesh, moves, before);
        }
        let (_, targets, _) = moves;
        let step = largest_move(before, targets);
        let scale = self.reach.min.abs().max(self.reach.max.abs()).max_element();
        let grown =
            state.collision_distance + state.max_edge * 1.001 + step + 4.0 * f32::EPSILON * scale;
        self.near_marks.start(mesh.face_count());
        let mut near: Vec<u32> = Vec::new();
        for &slot in searched {
            let search = Aabb::of_points(&[before[slot], targets[slot]]).expanded(grown);
            let (marks, gathered) = (&mut self.near_marks, &self.gathered);
            grid.for_each_in_box(search.min, search.max, |y| {
                for f in mesh.faces_around(y) {
                    if gathered.contains(f as usize) && marks.insert(f as usize) {
                        near.push(self.local_index[f as usize]);
                    }
                }
            });
        }
        near.sort_unstable();
        // Only these faces' entries are read (the searches meet no other): the rest keep
        // what an earlier step left until the whole region is filed.
        let sweeps: Vec<(Aabb, SweptTriangle)> = (near.iter())
            .map(|&l| sweep_of(mesh, self.faces[l as usize], moves, before))
            .collect();
        grow_to(&mut self.boxes, self.faces.len(), Aabb::EMPTY);
        grow_to(
            &mut self.swept,
            self.faces.len(),
            SweptTriangle::at_rest([Vec3::ZERO; 3]),
        );
        for (&l, &(swept_box, swept)) in near.iter().zip(&sweeps) {
            self.boxes[l as usize] = swept_box;
            self.swept[l as usize] = swept;
        }
        let (boxes, swept): (Vec<Aabb>, Vec<SweptTriangle>) = sweeps.into_iter().unzip();
        // Coarser cells than all the faces would get: the searches meet the same faces in
        // another order, which their results do not depend on ([`super::pull_back`]).
        let cell = self.cell.expect("a global grid gives the local one a cell");
        self.grid
            .build_some_swept((&boxes, &swept, &near), self.reach, cell);
        self.filed = Filing::Near;
    }

    /// Whether the proximity clamp's search of the region could find anything where the mesh
    /// is now: not when every layer in it is a clear sheet and alone there.
    pub(super) fn worth_searching_near(&self) -> bool {
        !(self.single_layer() && self.layers.iter().all(|&l| self.is_clear(l)))
    }

    /// Whether the backstop's search of the region could find a crossing where the mesh is
    /// now: not when every layer in it is a sheet and alone there.
    pub(super) fn worth_searching_crossings(&self) -> bool {
        !(self.single_layer() && self.layers.iter().all(|&l| self.is_sheet(l)))
    }

    /// Marks the region as not gathered for the step about to start.
    pub(super) fn forget(&mut self) {
        self.ready = false;
        self.sheets = None;
        self.no_sheet_this_step = false;
        self.cleared_vertices = 0;
    }

    /// Finds which layers are sheets where the mesh is now (`super::sheet`), unless known
    /// since the last move; all are taken as not when the stroke does not cull. Searches
    /// within a sheet are skipped until [`Region::positions_changed`].
    pub(super) fn find_sheets(&mut self, state: &StrokeState<'_>, mesh: &Mesh) {
        if self.sheets.is_some() {
            return;
        }
        // Pulling moves back seldom makes a sheet of what was none at the step's targets:
        // not worth another look this step.
        if self.no_sheet_this_step {
            self.sheets = Some(Vec::new());
            return;
        }
        let mut slopes = std::mem::take(&mut self.slopes);
        self.sheets = Some(if state.cull {
            super::sheet::find_sheets(state, mesh, self, &self.moving_layers, &mut slopes)
        } else {
            slopes.clear();
            Vec::new()
        });
        self.slopes = slopes;
        self.no_sheet_this_step = !self.sheets.iter().flatten().any(Option::is_some);
    }

    /// Whether the first look this step found a layer that is a sheet, whose searches
    /// were then skipped.
    pub(super) fn found_a_sheet(&self) -> bool {
        self.ready && self.sheets.is_some() && !self.no_sheet_this_step
    }

    /// Vertices of the region moved: which layers are sheets is not known any more.
    pub(super) fn positions_changed(&mut self) {
        self.sheets = None;
    }

    /// Whether `layer` is a sheet where the mesh is now, as far as known: none of its faces
    /// meet beyond what they share.
    pub(super) fn is_sheet(&self, layer: u32) -> bool {
        self.sheet(layer).is_some()
    }

    /// Whether `layer` is a clear sheet where the mesh is now, as far as known: none of its
    /// vertices comes within the collision distance of its faces outside its exclusion ring.
    pub(super) fn is_clear(&self, layer: u32) -> bool {
        self.sheet(layer).is_some_and(|sheet| sheet.clear)
    }

    pub(super) fn sheet(&self, layer: u32) -> Option<&Sheet> {
        self.sheets.as_ref()?.get(layer as usize)?.as_ref()
    }

    /// Whether every face of the region is of one layer.
    pub(super) fn single_layer(&self) -> bool {
        self.layers.len() <= 1
    }

    /// Whether a query of the grid over `query` finds only vertices this region gathered.
    pub(super) fn covers(&self, query: &Aabb) -> bool {
        self.ready && self.covers_box(query)
    }

    fn covers_box(&self, query: &Aabb) -> bool {
        query.min.cmpge(self.reach.min).all() && query.max.cmple(self.reach.max).all()
    }

    /// The vertices gathered (those the grid files in a cell overlapping the reach).
    pub(super) fn vertices(&self) -> &[u32] {
        &self.vertices
    }

    /// The faces around `vertices`, each once, in the order met; [`Region::is_listed`] then
    /// says whether a face is among them.
    pub(super) fn faces_around_once(
        &mut self,
        mesh: &Mesh,
        vertices: impl IntoIterator<Item = u32>,
    ) -> Vec<u32> {
        let marks = &mut self.face_marks;
        marks.start(mesh.face_count());
        vertices
            .into_iter()
            .flat_map(|v| mesh.faces_around(v))
            .filter(|&f| marks.insert(f as usize))
            .collect()
    }

    /// Whether `face` was among the last [`Region::faces_around_once`].
    pub(super) fn is_listed(&self, face: u32) -> bool {
        self.face_marks.contains(face as usize)
    }

    /// Index of a mesh face in this region, if it is in it.
    pub(super) fn local(&self, face: u32) -> Option<usize> {
        self.gathered
            .contains(face as usize)
            .then(|| self.local_index[face as usize] as usize)
    }

    /// Files the local faces `marks` holds (those a Jacobi pass changed) apart, for
    /// [`Region::changed_candidates`]; without the region's faces filed, forgets any.
    pub(super) fn file_changed(&mut self, marks: &[bool]) {
        debug_assert!(
            self.filed != Filing::Near,
            "changed faces filed before all the faces were"
        );
        let changed = &mut self.changed;
        changed.filed = self.filed == Filing::All;
        if !changed.filed {
            return;
        }
        changed.faces.clear();
        changed
            .faces
            .extend((0..marks.len() as u32).filter(|&l| marks[l as usize]));
        changed.boxes.clear();
        changed.swept.clear();
        for &l in &changed.faces {
            changed.boxes.push(self.boxes[l as usize]);
            changed.swept.push(self.swept[l as usize]);
        }
        if let Some(cell) = self.cell {
            let (boxes, swept) = (&changed.boxes, &changed.swept);
            changed.grid.build_swept(boxes, swept, self.reach, cell);
        }
    }

    /// Forgets the faces [`Region::file_changed`] filed (a new clamp).
    pub(super) fn forget_changed(&mut self) {
        self.changed.filed = false;
    }

    /// The local faces [`Region::file_changed`] filed whose box overlaps `query`, each once,
    /// but those of the layer `skip`; all of [`Region::candidates`] when none were filed.
    pub(super) fn changed_candidates(
        &self,
        (query, skip): (&Aabb, Option<u32>),
        scratch: &mut Scratch,
        mut f: impl FnMut(usize),
    ) {
        let changed = &self.changed;
        if !changed.filed {
            return self.candidates((query, skip), scratch, f);
        }
        let wanted = |k: u32| {
            let local = changed.faces[k as usize];
            Some(self.local_layers[local as usize]) != skip
                && changed.boxes[k as usize].overlaps(query)
        };
        if self.use_grid {
            scratch.seen.start(changed.faces.len());
            changed.grid.for_each_candidate(query, |k| {
                if scratch.seen.insert(k as usize) && wanted(k) {
                    f(changed.faces[k as usize] as usize);
                }
            });
        } else {
            for k in 0..changed.faces.len() as u32 {
                if wanted(k) {
                    f(changed.faces[k as usize] as usize);
                }
            }
        }
    }

    /// Local faces whose box overlaps `triangle`'s box and that are filed where `triangle`
    /// passes, each once, but those of the layer `skip`: those that can cross it.
    pub(super) fn candidates_along(
        &self,
        (triangle, skip): ([Vec3; 3], Option<u32>),
        scratch: &mut Scratch,
        mut f: impl FnMut(usize),
    ) {
        debug_assert!(
            self.filed != Filing::None,
            "a search before the faces were filed"
        );
        let query = Aabb::of_points(&triangle);
        if !self.use_grid {
            return self.candidates((&query, skip), scratch, f);
        }
        let swept = SweptTriangle::at_rest(triangle);
        scratch.seen.start(self.faces.len());
        let mut cells = std::mem::take(&mut scratch.cells);
        self.grid
            .for_each_candidate_along(&query, &swept, &mut cells, |local| {
                if self.wanted(local, (&query, skip)) && scratch.seen.insert(local as usize) {
                    f(local as usize);
                }
            });
        scratch.cells = cells;
    }

    /// Local faces whose box overlaps `query`, each once, but those of the layer `skip` (a
    /// search that skips a clear sheet's own faces leaves them before looking them up).
    pub(super) fn candidates(
        &self,
        (query, skip): (&Aabb, Option<u32>),
        scratch: &mut Scratch,
        mut f: impl FnMut(usize),
    ) {
        debug_assert!(
            self.filed != Filing::None,
            "a search before the faces were filed"
        );
        if self.use_grid {
            scratch.seen.start(self.faces.len());
            self.grid.for_each_candidate(query, |local| {
                if self.wanted(local, (query, skip)) && scratch.seen.insert(local as usize) {
                    f(local as usize);
                }
            });
        } else {
            for local in 0..self.faces.len() as u32 {
                if self.wanted(local, (query, skip)) {
                    f(local as usize);
                }
            }
        }
    }

    fn wanted(&self, local: u32, (query, skip): (&Aabb, Option<u32>)) -> bool {
        Some(self.local_layers[local as usize]) != skip
            && self.boxes[local as usize].overlaps(query)
    }
}

/// A vertex's search meets fewer faces than this, about: the box of its move grown by `d`,
/// a longest edge and the step's longest move, a few cells a side ([`Region::file_faces_near`]).
const FACES_NEAR_ONE_SEARCH: usize = 64;

/// The box of face `f` over the step (its corners where they start and, for those that move,
/// their targets; `before` holds the selection's starts) and its sweep.
fn sweep_of(mesh: &Mesh, f: u32, moves: StepMoves<'_>, before: &[Vec3]) -> (Aabb, SweptTriangle) {
    let (_, targets, target_of) = moves;
    let positions = mesh.positions();
    let mut corners = [Vec3::ZERO; 3];
    let mut moved = SweptTriangle::NO_MOVE;
    let mut swept_box = Aabb::EMPTY;
    for (corner, &v) in corners.iter_mut().zip(&mesh.faces()[f as usize]) {
        *corner = match target_of[v as usize] {
            INVALID => positions[v as usize],
            slot => {
                let (start, target) = (before[slot as usize], targets[slot as usize]);
                swept_box = swept_box.including(target);
                moved = moved.including(target - start);
                start
            }
        };
        swept_box = swept_box.including(*corner);
    }
    (
        swept_box,
        SweptTriangle {
            corners,
            moves: moved,
        },
    )
}

/// Faces one job sweeps at least ([`Region::file_faces`]): a face's sweep is well under a
/// microsecond.
const SWEEPS_PER_JOB: usize = 512;

/// Cell side of the per-step face grid, in edge lengths: a face box then covers one to two
/// cells per axis and a proximity query a handful.
const LOCAL_CELL_EDGES: f32 = 1.5;

/// Where vertex `v` was at the step's start: `before` for a selected one (through
/// `target_of`), its position for the others.
pub(super) fn start_position(mesh: &Mesh, v: u32, target_of: &[u32], before: &[Vec3]) -> Vec3 {
    match target_of[v as usize] {
        INVALID => mesh.positions()[v as usize],
        slot => before[slot as usize],
    }
}

pub(super) fn triangle(mesh: &Mesh, f: u32) -> [Vec3; 3] {
    mesh.face_positions(f as usize)
}

/// The distinct layer ids among `ids` (below `count`), ascending, into `out`.
fn layers_among(count: usize, ids: impl Iterator<Item = u32>, out: &mut Vec<u32>) {
    let mut present = vec![false; count];
    for id in ids {
        present[id as usize] = true;
    }
    out.clear();
    out.extend((0..count as u32).filter(|&l| present[l as usize]));
}

#[cfg(test)]
mod tests;
