//! Whole-mesh remeshing cell by cell: the mesh's box cut into cubes [`CELL_EDGES`]·L wide, and
//! each cube's vertices remeshed as one region, in a fixed order. A cell's region is small, so
//! its reference surface and face index stay small (one region of a million vertices spent a
//! quarter of its time walking an index of every face it had changed), and a cell that holds
//! one sheet and nothing else settles its edits' safety checks once (`zone`).
//!
//! Edges between two cells belong to neither region. A second round over cells shifted by half
//! a cell takes them where they are still out of band, with what the first left out of band
//! inside cells: its regions start at those edges' ends and take a ring around them, which
//! reaches across its own seams, so every edge out of band as it begins is in some region. A
//! round's cells are remeshed slab by slab on every core (`slabs`), or, on a mesh too short for
//! that, one after another in place; either way what runs in what order follows from the mesh
//! alone, never from the thread count.

use glam::{IVec3, Vec3};

use super::shape::ClosedParts;
use super::slabs::{self, Carried, Cell, Plan, Round};
use super::{
    Culling, Pass, Progress, RemeshReport, RemeshSets, RemeshSettings, Start, Zoning, out_of_band,
    remesh,
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
/// Iterations of the second round at most: it mends seams and stragglers on a mesh the first
/// has evened out. On the 1M-face torus a third iteration there took edge cv from 0.134 to
/// 0.130 for 4 % more time, and a third round (shifted by a quarter cell) on top to 0.125 for
/// 22 % more.
const SECOND_ROUND_ITERATIONS: usize = 2;

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
    // Before anything changes: a grid cell the grid refuses leaves the mesh as it was.
    SpatialHash::new(GRID_EDGES * settings.target_edge, 0)?;
    let closed = ClosedParts::find(mesh, &live);
    let report = remesh_by_cells(mesh, closed, settings, (start, culling), progress);
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
    closed: ClosedParts,
    settings: &RemeshSettings,
    (start, culling): (Start, Culling),
    progress: &mut dyn FnMut(Progress),
) -> RemeshReport {
    let mut report = RemeshReport::default();
    let mut carried = Carried {
        closed,
        longest: mesh.longest_edge(),
    };
    let width = CELL_EDGES * settings.target_edge;
    let rounds = [
        (0.0, start, settings.iterations),
        (
            0.5,
            Start::Subdivided,
            settings.iterations.min(SECOND_ROUND_ITERATIONS),
        ),
    ];
    for (round, (shift, start, iterations)) in rounds.into_iter().enumerate() {
        let settings = RemeshSettings {
            region_rings: rings(start),
            iterations,
            ..*settings
        };
        let mut cells = cells(mesh, width, shift);
        if start != Start::Everywhere {
            // A pass that starts out of band has nothing to do in a cell with no edge out of
            // band as the round begins, and is spared its copy. (An earlier cell's edit that
            // puts such a cell's edge out of band leaves it to the next round.)
            cells.retain(|(_, _, seeds)| {
                seeds
                    .iter()
                    .any(|&v| out_of_band(mesh, v, settings.target_edge))
            });
        }
        let count = cells.len();
        let mut done = 0;
        let mut tell = |cells_done: usize| {
            done += cells_done;
            progress(Progress {
                round: round + 1,
                rounds: rounds.len(),
                cell: done,
                cells: count,
            });
        };
        let round = Round {
            settings: &settings,
            start,
            culling,
            grid_cell: GRID_EDGES * settings.target_edge,
        };
        let reach = slabs::reach(&settings, settings.region_rings, carried.longest);
        let waves = match Plan::of(cells, (width, shift), reach, carried.longest) {
            Ok(plan) => run_slabs(mesh, plan, &mut carried, &round, &mut tell),
            Err(cells) => run_in_place(mesh, &cells, &mut carried, &round, &mut tell),
        };
        report.add(&waves);
    }
    report.passes = 1;
    report
}

/// A round's slabs, wave by wave, each wave on every core where its copies can be made and
/// put back, and in place where not.
fn run_slabs(
    mesh: &mut Mesh,
    plan: Plan,
    carried: &mut Carried,
    round: &Round<'_>,
    progress: &mut dyn FnMut(usize),
) -> RemeshReport {
    let mut report = RemeshReport::default();
    for wave in plan.waves() {
        let done =
            slabs::run_wave(mesh, (&plan, &wave), carried, round, progress).unwrap_or_else(|()| {
                let cells = wave.iter().flat_map(|&s| plan.cells_of(s));
                run_in_place(mesh, cells, carried, round, progress)
            });
        report.add(&done);
    }
    report
}

/// `cells` remeshed one after another in the mesh itself, with a grid of the mesh built for
/// them.
fn run_in_place<'c>(
    mesh: &mut Mesh,
    cells: impl IntoIterator<Item = &'c Cell>,
    carried: &mut Carried,
    round: &Round<'_>,
    progress: &mut dyn FnMut(usize),
) -> RemeshReport {
    let mut grid = SpatialHash::build(mesh, round.grid_cell)
        .expect("the cell size was checked before the rounds");
    let cells = (cells.into_iter()).map(|(_, core, seeds)| (core, seeds.as_slice()));
    let mut sets = RemeshSets::default();
    let mut done = || progress(1);
    slabs::remesh_cells(
        (mesh, &mut grid),
        cells,
        (&mut sets, carried),
        round,
        &mut done,
    )
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
fn cells(mesh: &Mesh, width: f32, shift: f32) -> Vec<Cell> {
    let cell_of = |p: Vec3| slabs::cell_of(p, (width, shift));
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
            let key = IVec3::new(x, y, z);
            (key, core, cell.iter().map(|&(_, v)| v).collect())
        })
        .collect()
}
