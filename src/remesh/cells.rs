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
use super::{Culling, Pass, Progress, RemeshReport, RemeshSets, RemeshSettings, Start, remesh};
use crate::geom::Aabb;
use crate::grid::SpatialHash;
use crate::mesh::{INVALID, Mesh};

/// A cell's width, in target edge lengths: wide enough that the zone's margin around it is a
/// small share of its faces, narrow enough that a sheet's normals stay in a cone across it.
const CELL_EDGES: f32 = 16.0;

/// Remeshes every vertex of `mesh`, cell by cell (the module's rounds). `start` says which of
/// a cell's vertices the first round begins at; the later ones begin where edges are out of
/// band.
pub(super) fn remesh_by_cells(
    mesh: &mut Mesh,
    grid: &mut SpatialHash,
    settings: &RemeshSettings,
    (start, culling): (Start, Culling),
    progress: &mut dyn FnMut(Progress),
) -> RemeshReport {
    let mut closed = ClosedParts::find(mesh, &live_vertices(mesh));
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
        // Every vertex of the first round's cells, where it begins everywhere; around the
        // vertices out of band, in the others.
        let settings = RemeshSettings {
            region_rings: u32::from(start != Start::Everywhere),
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
                zone,
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
        .filter(|&v| {
            !mesh.is_vertex_dead(v) && mesh.adjacency().vertex_corner[v as usize] != INVALID
        })
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
