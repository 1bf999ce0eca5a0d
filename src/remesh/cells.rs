//! Whole-mesh remeshing cell by cell: the mesh's box cut into cubes [`CELL_EDGES`]·L wide, and
//! each cube's vertices remeshed as one region, in a fixed order. A cell's region is small, so
//! its reference surface and face index stay small (one region of a million vertices spent a
//! quarter of its time walking an index of every face it had changed), and a cell that holds
//! one sheet and nothing else settles its edits' safety checks once (`zone`).
//!
//! Edges between two cells belong to neither region. A second round over cells shifted by half
//! a cell takes them where they are still out of band, and a third, shifted by a quarter, what
//! lies on both earlier rounds' seams (near where their planes cross) and what the second left
//! out of band. Each round's cells and their order follow from the mesh alone, never from the
//! thread count.

use glam::{IVec3, Vec3};

use super::shape::ClosedParts;
use super::zone::ZoneFinder;
use super::{
    Culling, Pass, Progress, RemeshReport, RemeshSets, RemeshSettings, Start, Zoning, remesh,
};
use crate::geom::Aabb;
use crate::grid::{GridError, SpatialHash};
use crate::mesh::Mesh;

/// A cell's width, in target edge lengths: wide enough that the zone's margin around it is a
/// small share of its faces, narrow enough that a sheet's normals stay in a cone across it.
const CELL_EDGES: f32 = 16.0;

/// Below this many vertices a mesh is remeshed as one region: cells pay for themselves where
/// one region's index grows large, and a small mesh has no seams to pay for.
const CELLS_FROM_VERTICES: usize = 20_000;
/// The vertex grid's cell, in target edge lengths, when remeshing by cells: each cell's
/// queries span dozens of edges (its reference surface, its zone), and a grid of edge-sized
/// cells spent most of their time walking empty ones.
const GRID_EDGES: f32 = 4.0;

/// Remeshes every vertex of `mesh`: a small mesh as one region, a larger one cell by cell (the
/// module's rounds). `start` says which vertices the (first round's) regions begin at; the
/// later rounds begin where edges are out of band.
pub(super) fn remesh_whole(
    mesh: &mut Mesh,
    settings: &RemeshSettings,
    (start, culling): (Start, Culling),
    progress: &mut dyn FnMut(Progress),
) -> Result<RemeshReport, GridError> {
    let live = live_vertices(mesh);
    if live.len() < CELLS_FROM_VERTICES {
        let mut grid = SpatialHash::build(mesh, settings.target_edge)?;
        let settings = RemeshSettings {
            region_rings: rings(start),
            ..*settings
        };
        let pass = Pass {
            start,
            sets: &mut RemeshSets::default(),
            closed: None,
            zone: Zoning::Off,
        };
        let (report, _) = remesh(mesh, &mut grid, &live, &settings, pass);
        progress(Progress {
            round: 1,
            rounds: 1,
            cell: 1,
            cells: 1,
        });
        return Ok(report);
    }
    let mut grid = SpatialHash::build(mesh, GRID_EDGES * settings.target_edge)?;
    let closed = ClosedParts::find(mesh, &live);
    let report = remesh_by_cells(
        mesh,
        (&mut grid, closed),
        settings,
        (start, culling),
        progress,
    );
    Ok(report)
}

/// Every vertex of the regions `start` begins at, where it begins everywhere; around them, by
/// one ring, where it begins out of band.
fn rings(start: Start) -> u32 {
    u32::from(start != Start::Everywhere)
}

/// `closed`: the mesh's closed components, found once for every cell.
fn remesh_by_cells(
    mesh: &mut Mesh,
    (grid, mut closed): (&mut SpatialHash, ClosedParts),
    settings: &RemeshSettings,
    (start, culling): (Start, Culling),
    progress: &mut dyn FnMut(Progress),
) -> RemeshReport {
    let mut sets = RemeshSets::default();
    let mut zones = ZoneFinder::default();
    let mut report = RemeshReport::default();
    let mut longest_edge = mesh.longest_edge();
    let width = CELL_EDGES * settings.target_edge;
    let rounds = [
        (0.0, start),
        (0.5, Start::Subdivided),
        (0.25, Start::Subdivided),
    ];
    for (round, (shift, start)) in rounds.into_iter().enumerate() {
        let settings = RemeshSettings {
            region_rings: rings(start),
            ..*settings
        };
        let cells = cells(mesh, width, shift);
        let count = cells.len();
        for (cell, (core, seeds)) in cells.into_iter().enumerate() {
            let zone = match culling {
                Culling::On => zones.find(mesh, grid, &core, (settings.target_edge, longest_edge)),
                Culling::Off => None,
            };
            let pass = Pass {
                start,
                sets: &mut sets,
                closed: Some(&mut closed),
                zone: Zoning::Cell(zone),
            };
            let (done, _) = remesh(mesh, grid, &seeds, &settings, pass);
            longest_edge = longest_edge.max(done.longest_edge);
            report.add(&done);
            progress(Progress {
                round: round + 1,
                rounds: rounds.len(),
                cell: cell + 1,
                cells: count,
            });
        }
    }
    report.passes = 1;
    report
}

/// The vertices with faces.
fn live_vertices(mesh: &Mesh) -> Vec<u32> {
    (0..mesh.vertex_count() as u32)
        .filter(|&v| mesh.is_vertex_live(v))
        .collect()
}

/// The live vertices grouped by the cube `width` wide they lie in, the cubes shifted by
/// `shift` of a width, each with its box; in the cubes' order (x, then y, then z), each
/// cube's vertices ascending, so the order never depends on anything but the mesh.
fn cells(mesh: &Mesh, width: f32, shift: f32) -> Vec<(Aabb, Vec<u32>)> {
    let cell_of = |p: Vec3| (p / width + shift).floor().as_ivec3();
    let mut keyed: Vec<((i32, i32, i32), u32)> = live_vertices(mesh)
        .into_iter()
        .map(|v| {
            let c = cell_of(mesh.positions()[v as usize]);
            ((c.x, c.y, c.z), v)
        })
        .collect();
    keyed.sort_unstable();
    keyed
        .chunk_by(|a, b| a.0 == b.0)
        .map(|cell| {
            let (x, y, z) = cell[0].0;
            let lo = (IVec3::new(x, y, z).as_vec3() - shift) * width;
            let core = Aabb {
                min: lo,
                max: lo + Vec3::splat(width),
            };
            (core, cell.iter().map(|&(_, v)| v).collect())
        })
        .collect()
}
