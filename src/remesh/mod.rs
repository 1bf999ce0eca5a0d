//! Local adaptive isotropic remeshing after each stroke (Dunyach et al. 2013, in the loop of
//! Botsch & Kobbelt 2004; docs/design.md, "Remeshing"): within the faces around every vertex the stroke touched,
//! plus a ring, split edges longer than 4/3·L, collapse edges shorter than 4/5·L, flip edges
//! toward valence 6 (4 on boundaries), and relax vertices tangentially with projection back onto
//! the surface as it was before remeshing. L stays constant: sLayer's edge length assumption.
//!
//! Remeshing never creates interpenetration: a vertex moved by a collapse or by relaxation may
//! not come closer than the collision distance to another layer (or to a part of its own layer
//! outside its neighbourhood) than it already was, and the triangles a flip or a collapse
//! creates are tested exactly against the other layers' triangles nearby. The layer gap is kept
//! both ways: no other layer's vertex within the collision distance of the faces an edit makes
//! may be nearer to them than to the faces they replace, and a split's new vertex no nearer to
//! another layer than its edge's ends. The grid is kept up to date through every edit.
//!
//! Remeshing keeps the shape (`shape`): no edit moves the surface more than
//! [`SHAPE_TOLERANCE`]·L from where it was, nor changes a closed component's volume past
//! [`VOLUME_TOLERANCE`] or takes it below [`MIN_CLOSED_FACES`] faces.

mod cells;
mod edits;
mod quality;
mod reference;
mod refine;
mod safety;
mod shape;
mod slabs;
mod zone;

use std::time::Instant;

use glam::Vec3;
use serde::Serialize;

use crate::collide::Stamps;

use crate::geom::Aabb;
use crate::grid::{GridError, SpatialHash};
use crate::mesh::{Mesh, next, prev};
pub use quality::{
    AngleSummary, Distance, Quality, Surface, VALENCE_BUCKETS, smallest_angle_degrees,
};
use reference::ReferenceSurface;
pub use refine::{subdivide, subdivision_levels};
use shape::ClosedParts;
pub use shape::{MIN_CLOSED_FACES, SHAPE_TOLERANCE, VOLUME_TOLERANCE};
use zone::Zone;

/// Edge band of Botsch & Kobbelt: split above 4/3·L, collapse below 4/5·L.
pub const SPLIT_ABOVE: f32 = 4.0 / 3.0;
/// How long an edge (× L) the collapses of a whole-mesh remesh's first iteration may leave at
/// their survivor, where it starts everywhere (a subdivided mesh is as even as its input);
/// later ones, like Botsch & Kobbelt's, and a stroke's, leave none past [`SPLIT_ABOVE`]. An
/// evenly stretched grid (a torus's top: edges of 0.72, 1.02 and 1.25·L, every valence 6) is a
/// fixed point of the four edits under 4/3: no edge is long, no flip betters a valence,
/// relaxation leaves a regular grid where it is, and collapsing a short edge would leave one of
/// 1.49·L. A third of such a mesh's edges stayed short. The next iteration's splits take what
/// this leaves past 4/3·L.
const FIRST_COLLAPSE_LIMIT: f32 = 1.5;
/// Where along an edge a split puts its new vertex.
const SPLIT_AT: f32 = 0.5;
pub const COLLAPSE_BELOW: f32 = 4.0 / 5.0;
/// A collapse or flip may not turn a face's normal by more than this (cosine).
const MIN_NORMAL_COSINE: f32 = 0.5;
/// A flip may only replace a nearly flat pair of faces (cosine of the dihedral deviation), so
/// the surface keeps its shape.
const FLIP_FLATNESS_COSINE: f32 = 0.94;
/// Relaxation moves shorter than this share of L are not worth their collision checks.
const RELAX_MIN_MOVE: f32 = 0.05;
/// How many faces a stroke's region may gather, per region vertex and at least, to find its
/// sheet zone: each of its edits' checks costs about what gathering a hundred faces does.
const ZONE_FACES_PER_REGION_VERTEX: usize = 32;
const ZONE_FACES_MIN: usize = 16_384;
/// Faces thinner than this share of L² are not created.
const MIN_AREA_SHARE: f32 = 0.01;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RemeshSettings {
    /// Target edge length `L`.
    pub target_edge: f32,
    /// Split / collapse / flip / relax rounds.
    pub iterations: usize,
    /// Rings of vertices added around the touched ones.
    pub region_rings: u32,
    /// Collision distance (world units) and the neighbourhood ring a vertex skips.
    pub collision_distance: f32,
    pub exclusion_ring: u32,
    /// Splits the pass may make at most: a stroke's share of its bound on the faces it
    /// creates (`PipelineSettings::new_faces_per_stroke`); unbounded elsewhere.
    pub max_splits: usize,
}

impl RemeshSettings {
    pub fn new(target_edge: f32) -> Self {
        RemeshSettings {
            target_edge,
            iterations: 3,
            region_rings: 2,
            collision_distance: target_edge,
            exclusion_ring: 1,
            max_splits: usize::MAX,
        }
    }
}

/// What a remesh did.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RemeshReport {
    /// Remeshing passes summed here (one per stroke or per sample).
    pub passes: usize,
    /// Whole levels of 1-to-4 subdivision before the passes ([`remesh_all`] refining by a
    /// large factor).
    pub subdivisions: u32,
    pub region_vertices: usize,
    pub splits: usize,
    pub collapses: usize,
    pub flips: usize,
    pub relaxed: usize,
    /// Moves and edits refused because they would have come too close to another surface.
    pub refused: usize,
    /// Edits refused because they would have moved the surface past [`SHAPE_TOLERANCE`],
    /// changed a closed component's volume past [`VOLUME_TOLERANCE`], or left it fewer than
    /// [`MIN_CLOSED_FACES`] faces.
    pub shape_refused: usize,
    /// Edits whose safety checks a sheet zone settled (whole-mesh remeshing, `zone`).
    pub culled: usize,
    /// Slabs of a whole-mesh remesh copied out and remeshed beside each other, on every core
    /// (`slabs`); 0 where the mesh was too small to cut into them.
    pub slabs: usize,
    /// Passes that stopped splitting at [`RemeshSettings::max_splits`], leaving long edges.
    pub growth_capped: usize,
    /// Longest edge among the faces around the region afterwards (the pipeline's running
    /// bound on edge lengths).
    pub longest_edge: f32,
    pub millis: f64,
}

impl RemeshReport {
    pub fn add(&mut self, other: &RemeshReport) {
        self.passes += other.passes;
        self.subdivisions += other.subdivisions;
        self.region_vertices += other.region_vertices;
        self.splits += other.splits;
        self.collapses += other.collapses;
        self.flips += other.flips;
        self.relaxed += other.relaxed;
        self.refused += other.refused;
        self.shape_refused += other.shape_refused;
        self.culled += other.culled;
        self.slabs += other.slabs;
        self.growth_capped += other.growth_capped;
        self.longest_edge = self.longest_edge.max(other.longest_edge);
        self.millis += other.millis;
    }
}

/// Remeshes the region around `seeds` (the vertices a stroke moved), keeping `grid` exact.
/// Returns what it did and every vertex whose position, normal, faces or neighbours it changed
/// (ascending; the vertices it added and removed included), for copies of the mesh kept
/// elsewhere (the GPU's) to be patched.
pub fn remesh_region(
    mesh: &mut Mesh,
    grid: &mut SpatialHash,
    seeds: &[u32],
    settings: &RemeshSettings,
) -> (RemeshReport, Vec<u32>) {
    let pass = (settings, None);
    remesh_region_with(mesh, grid, seeds, pass, &mut RemeshSets::default())
}

/// [`remesh_region`] with sets kept from earlier passes: a pass then costs what its region
/// does, never what the mesh does (a stroke on 16M faces remeshes as fast as on 250K). Where
/// `culling` gives the mesh's longest edge, a sheet zone settles the safety checks of the
/// edits it vouches for where the region and everything within the zone's margin of it is
/// one sheet of one layer (`zone`): a stroke on a single sheet need not pay for the checks a
/// stack of layers needs.
pub fn remesh_region_with(
    mesh: &mut Mesh,
    grid: &mut SpatialHash,
    seeds: &[u32],
    (settings, culling): (&RemeshSettings, Option<f32>),
    sets: &mut RemeshSets,
) -> (RemeshReport, Vec<u32>) {
    let pass = Pass {
        start: Start::OutOfBand,
        sets,
        closed: None,
        zone: culling.map_or(Zoning::Off, Zoning::Region),
    };
    remesh(mesh, grid, seeds, settings, pass)
}

/// Remeshes `piece`, a mesh a layer tool made to add to another (which checks it exactly
/// against that mesh afterwards), where its edges are out of band. Where the piece is one sheet
/// (`zone`'s lone sheet) the zone vouches for the edits that keep it one: the piece has nothing
/// else to come near, and a million-face layer's new patch need not pay for the checks a
/// stack of layers needs.
pub fn remesh_piece(
    piece: &mut Mesh,
    settings: &RemeshSettings,
) -> Result<RemeshReport, GridError> {
    let mut grid = SpatialHash::build(piece, settings.target_edge)?;
    let every: Vec<u32> = (0..piece.vertex_count() as u32).collect();
    let pass = Pass {
        start: Start::OutOfBand,
        sets: &mut RemeshSets::default(),
        closed: None,
        zone: Zoning::LoneSheet,
    };
    let (report, _) = remesh(piece, &mut grid, &every, settings, pass);
    Ok(report)
}

/// The per-vertex sets of a remeshing pass (which vertices are in its region, which an edit
/// changed, which relaxation may move), emptied in O(1) between passes.
#[derive(Debug, Clone, Default)]
pub struct RemeshSets {
    in_region: Stamps,
    dirty: Stamps,
    movable: Stamps,
    /// The sets a region's sheet zone is found with ([`remesh_region_with`]).
    zones: zone::ZoneFinder,
}

impl RemeshSets {
    /// Sizes the sets for `mesh` ahead of the first pass (set-up, not a stroke's).
    pub fn size_for(&mut self, mesh: &Mesh) {
        for set in [&mut self.in_region, &mut self.dirty, &mut self.movable] {
            set.size_for(mesh.vertex_count());
        }
    }
}

/// Where remeshing starts: after a stroke, at the vertices with an edge outside the band (the
/// rest of the stroke's footprint is already as the remesher would leave it, and is left
/// alone); for a whole-mesh remesh, everywhere, or, on a mesh just subdivided (as even as its
/// input), at its vertices out of band again.
#[derive(Clone, Copy, PartialEq)]
enum Start {
    OutOfBand,
    Everywhere,
    Subdivided,
}

/// How one remeshing pass runs, besides its region.
struct Pass<'s> {
    start: Start,
    sets: &'s mut RemeshSets,
    /// The closed components' volumes, kept across the passes of a whole-mesh remesh (one
    /// pass per cell); `None` finds those of the region.
    closed: Option<&'s mut ClosedParts>,
    /// Which sheet zone vouches for the pass's edits.
    zone: Zoning,
}

/// Which sheet zone vouches for a pass's edits, sparing them their safety checks (`zone`).
enum Zoning {
    /// None: every edit is checked (a stroke's remesh).
    Off,
    /// The zone of a whole-mesh remesh's cell, found before the pass: once an edit it cannot
    /// vouch for has passed its checks, the rest of the cell's pass is checked.
    Cell(Option<Zone>),
    /// The region's, found once its region is known (a stroke's remesh): the region's box
    /// is the cell. The longest edge of the mesh comes with it.
    Region(f32),
    /// The whole mesh, when it is a lone sheet (`zone`): found again before each stage of
    /// the pass (splits, collapses, flips, relaxation) where an edit it could not vouch for
    /// ended it. A piece's rim edits come early in a stage, and its interior is most of it.
    LoneSheet,
}

fn remesh(
    mesh: &mut Mesh,
    grid: &mut SpatialHash,
    seeds: &[u32],
    settings: &RemeshSettings,
    mut pass: Pass<'_>,
) -> (RemeshReport, Vec<u32>) {
    let started = Instant::now();
    let kept = pass.closed.as_deref_mut().map(std::mem::take);
    let mut remesher = Remesher::new(mesh, grid, seeds, settings, (pass.start, pass.sets), kept);
    remesher.zone = match pass.zone {
        Zoning::Off => None,
        Zoning::Cell(zone) => zone,
        Zoning::Region(longest) => remesher.region_zone(longest),
        Zoning::LoneSheet => Zone::of_lone_sheet(remesher.mesh, settings.target_edge),
    };
    remesher.lone_sheet = matches!(pass.zone, Zoning::LoneSheet) && remesher.zone.is_some();
    remesher.zone_keeps_own_gap = matches!(pass.zone, Zoning::Region(_));
    for round in 0..settings.iterations {
        let opening = round == 0 && pass.start == Start::Everywhere && settings.iterations > 1;
        remesher.collapse_limit = if opening {
            FIRST_COLLAPSE_LIMIT
        } else {
            SPLIT_ABOVE
        };
        let edits = remesher.edit_count();
        remesher.renew_zone();
        remesher.split_long_edges();
        remesher.renew_zone();
        remesher.collapse_short_edges();
        remesher.renew_zone();
        remesher.flip_toward_regular_valence();
        // Relaxation follows edits: a round that changed nothing (after the first, which
        // relaxes what the stroke left out of band) has converged.
        if round > 0 && remesher.edit_count() == edits {
            break;
        }
        remesher.renew_zone();
        remesher.relax();
    }
    if let Some(closed) = pass.closed {
        *closed = std::mem::take(&mut remesher.closed);
    }
    let (mut report, changed) = remesher.finish();
    report.passes = 1;
    report.millis = started.elapsed().as_secs_f64() * 1e3;
    (report, changed)
}

/// Why a whole-mesh remesh could not run.
#[derive(Debug, thiserror::Error)]
pub enum RemeshError {
    /// The grid refused the target: no positive finite length.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// Subdividing made no valid mesh (the input was not one).
    #[error("subdividing: {0}")]
    Subdivision(#[from] crate::mesh::MeshError),
}

/// Remeshes a whole mesh to edge length `target_edge` (`slayer remesh`). A target several
/// times shorter than the mean edge is first approached by whole levels of subdivision
/// ([`subdivision_levels`], [`subdivide`]), then the passes run over every vertex, cell by
/// cell (`cells`).
pub fn remesh_all(mesh: &mut Mesh, settings: &RemeshSettings) -> Result<RemeshReport, RemeshError> {
    remesh_all_with(mesh, settings, Culling::On, &mut |_| {})
}

/// How far a whole-mesh remesh has come: `cell` of `cells` in round `round` (from 1) of
/// `rounds` (`cells`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    pub round: usize,
    pub rounds: usize,
    pub cell: usize,
    pub cells: usize,
}

/// Whether a whole-mesh remesh lets sheet zones settle the safety checks of their edits
/// (`zone`). Off only to show that they change nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Culling {
    On,
    Off,
}

/// [`remesh_all`], with the zones' culling as `culling` says, telling `progress` after each
/// cell.
pub fn remesh_all_with(
    mesh: &mut Mesh,
    settings: &RemeshSettings,
    culling: Culling,
    progress: &mut dyn FnMut(Progress),
) -> Result<RemeshReport, RemeshError> {
    // Before anything changes: a target the grid refuses leaves the mesh as it was.
    SpatialHash::new(settings.target_edge, 0)?;
    let started = Instant::now();
    let levels = subdivision_levels(mesh.edge_length_stats().mean as f32, settings.target_edge);
    for _ in 0..levels {
        *mesh = subdivide(mesh)?;
    }
    // A subdivided mesh is as even as its input: only where an edge left the band is there
    // work, as after a stroke (most of a million vertices need nothing).
    let start = if levels > 0 {
        Start::Subdivided
    } else {
        Start::Everywhere
    };
    let report = cells::remesh_whole(mesh, settings, (start, culling), progress)?;
    mesh.compact();
    // The cells' passes' times add up across threads: the remesh took what the clock says.
    Ok(RemeshReport {
        subdivisions: levels,
        millis: started.elapsed().as_secs_f64() * 1e3,
        ..report
    })
}

struct Remesher<'a> {
    mesh: &'a mut Mesh,
    /// The region (`in_region`), the vertices whose neighbourhood an edit changed or that
    /// started out of band (`dirty`: flips look at their edges and relaxation moves them and
    /// their neighbours), the vertices a relaxation round may move (`movable`).
    sets: &'a mut RemeshSets,
    grid: &'a mut SpatialHash,
    settings: RemeshSettings,
    /// Region vertices (grows with splits; dead ones are skipped).
    region: Vec<u32>,
    dirty_list: Vec<u32>,
    /// Collapses refused for coming too close to another surface, by vertex pair: what stopped
    /// them does not go away by remeshing, so later rounds do not retry them.
    refused_collapses: rustc_hash::FxHashSet<(u32, u32)>,
    surface: ReferenceSurface,
    /// The closed components the region is on: their volumes and face counts.
    closed: ClosedParts,
    report: RemeshReport,
    scratch: Vec<u32>,
    near: Vec<NearFace>,
    /// The faces around a moving vertex and what they become ([`Remesher::move_is_safe`]).
    move_lists: (Vec<u32>, Vec<IdTriangle>),
    /// A whole-mesh remesh ([`Start::Everywhere`], [`Start::Subdivided`]): relaxation passes
    /// over vertices whose move is short before projecting them.
    whole: bool,
    /// The sheet zone the region lies in, while its edits keep it one (`zone`).
    zone: Option<Zone>,
    /// The whole mesh was a lone sheet when the pass began: its zone is found again before
    /// each stage ([`Zoning::LoneSheet`]). A mesh that was not one is not searched again.
    lone_sheet: bool,
    /// A move the zone vouches for is still kept from its own layer beyond its exclusion
    /// ring (`safety`), so that the pass is the one every check would make: a stroke's
    /// remesh, which `PipelineSettings::cull` must not change. A whole-mesh remesh lets the
    /// zone settle that too (a sheet's second ring within `d` of a vertex is no crossing).
    zone_keeps_own_gap: bool,
    /// The longest edge (× L) a collapse may leave at its survivor this iteration.
    collapse_limit: f32,
}

impl<'a> Remesher<'a> {
    fn new(
        mesh: &'a mut Mesh,
        grid: &'a mut SpatialHash,
        seeds: &[u32],
        settings: &RemeshSettings,
        (start, sets): (Start, &'a mut RemeshSets),
        closed: Option<ClosedParts>,
    ) -> Self {
        let live = |v: u32| (v as usize) < mesh.vertex_count() && !mesh.is_vertex_dead(v);
        let out_of_band = |v: u32| out_of_band(mesh, v, settings.target_edge);
        // The region grows from the vertices that need work, not from everything the stroke
        // touched: most of a stroke's footprint keeps its edges in band.
        let in_region = &mut sets.in_region;
        in_region.start(mesh.vertex_count());
        sets.dirty.start(mesh.vertex_count());
        let mut region = Vec::new();
        for &v in seeds {
            if live(v)
                && !in_region.contains(v as usize)
                && (start == Start::Everywhere || out_of_band(v))
            {
                in_region.insert(v as usize);
                region.push(v);
            }
        }
        let starting = region.clone();
        let mut frontier = region.clone();
        for _ in 0..settings.region_rings {
            let mut next_frontier = Vec::new();
            for &v in &frontier {
                for u in mesh.neighbours(v) {
                    if in_region.insert(u as usize) {
                        region.push(u);
                        next_frontier.push(u);
                    }
                }
            }
            frontier = next_frontier;
        }
        region.sort_unstable();
        let surface = ReferenceSurface::capture(mesh, grid, &region, settings);
        let closed = closed.unwrap_or_else(|| ClosedParts::find(mesh, &region));
        let mut remesher = Remesher {
            report: RemeshReport {
                region_vertices: region.len(),
                ..RemeshReport::default()
            },
            mesh,
            grid,
            settings: *settings,
            region,
            sets,
            dirty_list: Vec::new(),
            refused_collapses: Default::default(),
            surface,
            closed,
            scratch: Vec::new(),
            near: Vec::new(),
            move_lists: Default::default(),
            whole: start != Start::OutOfBand,
            zone: None,
            lone_sheet: false,
            zone_keeps_own_gap: false,
            collapse_limit: SPLIT_ABOVE,
        };
        for v in starting {
            remesher.mark_dirty(v);
        }
        remesher
    }

    /// The sheet zone around the region's box, if gathering it costs no more than a few
    /// times the region's own faces.
    fn region_zone(&mut self, longest_edge: f32) -> Option<Zone> {
        let positions = self.mesh.positions();
        let live = self.region.iter().filter(|&&v| self.mesh.is_vertex_live(v));
        let core = live.fold(Aabb::EMPTY, |b, &v| b.including(positions[v as usize]));
        if core.is_empty() {
            return None;
        }
        let budget = ZONE_FACES_PER_REGION_VERTEX * self.region.len() + ZONE_FACES_MIN;
        let lengths = (self.settings.target_edge, longest_edge);
        (self.sets.zones).find_within(self.mesh, self.grid, &core, lengths, budget)
    }

    /// Finds a lone sheet's zone again where an edit it could not vouch for ended it.
    fn renew_zone(&mut self) {
        if self.lone_sheet && self.zone.is_none() {
            self.zone = Zone::of_lone_sheet(self.mesh, self.settings.target_edge);
        }
    }

    fn edit_count(&self) -> usize {
        self.report.splits + self.report.collapses + self.report.flips
    }

    fn mark_dirty(&mut self, v: u32) {
        self.sets.dirty.size_for(v as usize + 1);
        if self.sets.dirty.insert(v as usize) {
            self.dirty_list.push(v);
        }
    }

    /// The faces around `v` changed (an edit moved, added or rewired `v`): the reference
    /// surface finds them where they are now.
    fn refile_faces_around(&mut self, v: u32) {
        let faces: Vec<u32> = self.mesh.faces_around(v).collect();
        self.surface.faces_changed(self.mesh, faces);
    }

    /// Marks `v` and its neighbours dirty: an edit at `v` changed all their one-rings.
    fn mark_dirty_around(&mut self, v: u32) {
        self.mark_dirty(v);
        for u in self.mesh.neighbours(v) {
            self.mark_dirty(u);
        }
    }

    fn in_region(&self, v: u32) -> bool {
        self.sets.in_region.contains(v as usize)
    }

    fn is_dirty(&self, v: u32) -> bool {
        self.sets.dirty.contains(v as usize)
    }

    /// Recomputes the normals around the region; returns the report and every vertex whose
    /// data changed: the region (edits stay within it, relaxation moves only it; removed
    /// vertices stay listed) and every vertex of a face around it (their faces and one-rings
    /// change with the region's edges, and their normals are recomputed).
    fn finish(self) -> (RemeshReport, Vec<u32>) {
        let live: Vec<u32> = self
            .region
            .iter()
            .copied()
            .filter(|&v| !self.mesh.is_vertex_dead(v))
            .collect();
        let mut refresh: Vec<u32> = live
            .iter()
            .flat_map(|&v| {
                self.mesh
                    .faces_around(v)
                    .flat_map(|f| self.mesh.faces()[f as usize])
            })
            .collect();
        refresh.sort_unstable();
        refresh.dedup();
        self.mesh.recompute_normals_at(&refresh);
        let mut changed = refresh;
        changed.extend_from_slice(&self.region);
        changed.sort_unstable();
        changed.dedup();
        let mut report = self.report;
        report.longest_edge = live
            .iter()
            .flat_map(|&v| self.mesh.faces_around(v))
            .map(|f| {
                let [a, b, c] = self.mesh.face_positions(f as usize);
                a.distance(b).max(b.distance(c)).max(c.distance(a))
            })
            .fold(0.0, f32::max);
        (report, changed)
    }

    /// Edges with both ends in the region, each once, as corners. (Edges leaving the region
    /// are left alone: the ring around the touched vertices is the margin.)
    fn region_edges(&self) -> Vec<u32> {
        let mut edges = Vec::new();
        for &v in &self.region {
            if self.mesh.is_vertex_live(v) {
                self.push_edges_at(v, &mut edges);
            }
        }
        edges
    }

    /// The region edges at `v` that `v` owns (the lower-numbered end), as corners.
    fn push_edges_at(&self, v: u32, edges: &mut Vec<u32>) {
        let owned = |u: u32| v < u && self.in_region(u);
        for c in self.mesh.adjacency().corners_around(v) {
            // Around v, corner c's face holds edge (v, next), opposite prev(c).
            if owned(self.mesh.corner_vertex(next(c))) {
                edges.push(prev(c));
            }
        }
        if self.mesh.is_boundary_vertex(v) {
            // The boundary edge the fan starts from, (prev(first), v), opposite next(first).
            let first = self.mesh.adjacency().vertex_corner[v as usize];
            if owned(self.mesh.corner_vertex(prev(first))) {
                edges.push(next(first));
            }
        }
    }

    fn length(&self, corner: u32) -> f32 {
        let (a, b) = self.mesh.edge_vertices(corner);
        self.mesh.positions()[a as usize].distance(self.mesh.positions()[b as usize])
    }

    fn add_to_region(&mut self, v: u32) {
        self.sets.in_region.size_for(v as usize + 1);
        if self.sets.in_region.insert(v as usize) {
            self.region.push(v);
        }
    }
}

/// Whether an edge at `v` lies outside the band around `target_edge` that remeshing keeps
/// edges in: where a pass that starts out of band starts.
fn out_of_band(mesh: &Mesh, v: u32, target_edge: f32) -> bool {
    let band = COLLAPSE_BELOW * target_edge..=SPLIT_ABOVE * target_edge;
    let p = mesh.positions()[v as usize];
    mesh.neighbours(v)
        .into_iter()
        .any(|u| !band.contains(&p.distance(mesh.positions()[u as usize])))
}

/// A face as its vertex ids and their positions: what an edit would make.
type IdTriangle = ([u32; 3], [Vec3; 3]);

/// A face near an edit, as it is now.
#[derive(Debug, Clone, Copy)]
struct NearFace {
    face: u32,
    ids: [u32; 3],
    at: [Vec3; 3],
    bounds: Aabb,
}

fn normal(t: [Vec3; 3]) -> Vec3 {
    (t[1] - t[0]).cross(t[2] - t[0])
}
