//! Whole-mesh remeshing on every core (issue 28): a round's cells (`cells`) grouped into
//! *slabs*, runs of whole cells along the axis the cells spread most along, and the slabs
//! taken in two *waves*, the even ones and then the odd ones. Within a wave, each slab's
//! faces and all around them within [`reach`] are copied out ([`Mesh::copy_patch`]), the
//! slab's cells are remeshed in the copy as they would be in the mesh, and the copies are put
//! back in slab order ([`Mesh::put_back`]).
//!
//! Why that is the same as remeshing the slab in place: a cell's pass writes near the cell
//! and reads (its zone, its reference surface, the faces its safety checks test) near what it
//! writes, all within `reach` of the cell, so a copy of every face within `reach` (and an
//! edge) of the slab's cells holds all the passes read. Two slabs of a wave are a whole slab
//! apart, wider than both their copies' margins: neither reads what the other writes, and
//! their copies share no face. A pass that wrote farther than `reach` would have changed its
//! copy's rim, which putting back refuses (the wave then runs in place). The closed
//! components' volume bounds are split between a wave's slabs (`ClosedParts::share`), so
//! together they keep to them.
//!
//! Which cells make a slab, the waves and the order copies are put back in follow from the
//! mesh alone; the thread count only decides how many slabs are worked at once, so the result
//! is the same, bit for bit, on one thread or many.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

use glam::{IVec3, Vec3};

use super::shape::ClosedParts;
use super::zone::MARGIN_EDGES;
use super::{Culling, Pass, RemeshReport, RemeshSets, RemeshSettings, Start, Zoning, remesh};
use crate::geom::Aabb;
use crate::grid::SpatialHash;
use crate::mesh::{Mesh, Patch};
use rustc_hash::FxHashSet;

/// A cell of a round: its integer position, its box, its vertices.
pub(super) type Cell = (IVec3, Aabb, Vec<u32>);

/// Fewer slabs than this and a round runs in place: a wave of one slab is one thread's work
/// with a copy's cost on top.
const MIN_SLABS: usize = 4;

/// What every cell's pass in a round shares.
pub(super) struct Round<'a> {
    pub settings: &'a RemeshSettings,
    pub start: Start,
    pub culling: Culling,
    /// The vertex grid's cell, for the copies' grids.
    pub grid_cell: f32,
}

/// What a whole-mesh remesh carries from cell to cell: the closed components' volume
/// budgets, and a bound on every edge of the mesh as the passes leave it.
pub(super) struct Carried {
    pub closed: ClosedParts,
    pub longest: f32,
}

/// Remeshes `cells` (a box and its seeds each) one after another in `mesh`, indexed by
/// `grid`; `done` hears of each cell. The same loop runs a round in place and a slab in its
/// copy.
pub(super) fn remesh_cells<'c, Seeds: AsRef<[u32]>>(
    (mesh, grid): (&mut Mesh, &mut SpatialHash),
    cells: impl Iterator<Item = (&'c Aabb, Seeds)>,
    (sets, carried): (&mut RemeshSets, &mut Carried),
    round: &Round<'_>,
    done: &mut dyn FnMut(),
) -> RemeshReport {
    let settings = round.settings;
    let mut report = RemeshReport::default();
    for (core, seeds) in cells {
        let lengths = (settings.target_edge, carried.longest);
        let zone = match round.culling {
            Culling::On => sets.zones.find(mesh, grid, core, lengths),
            Culling::Off => None,
        };
        let pass = Pass {
            start: round.start,
            sets: &mut *sets,
            closed: Some(&mut carried.closed),
            zone: Zoning::Cell(zone),
        };
        let (pass_report, _) = remesh(mesh, grid, seeds.as_ref(), settings, pass);
        carried.longest = carried.longest.max(pass_report.longest_edge);
        report.add(&pass_report);
        done();
    }
    report
}

/// The cell of a lattice `width` wide shifted by `shift` of a width that `p` lies in.
pub(super) fn cell_of(p: Vec3, (width, shift): (f32, f32)) -> IVec3 {
    (p / width + shift).floor().as_ivec3()
}

/// A round's slabs: the cells of each, in the round's order, and what each copy must hold.
pub(super) struct Plan {
    axis: usize,
    /// The round's cells: `width` wide, shifted by `shift` of a width.
    lattice: (f32, f32),
    slabs: Vec<Slab>,
}

struct Slab {
    cells: Vec<Cell>,
    /// The span along the axis a copy may hold: the cells' and the margin each side.
    span: (f32, f32),
    /// The cells within the margin of one of `cells`: a copy holds their vertices.
    near: FxHashSet<IVec3>,
}

/// How far (world units) a cell's pass may reach past the cell, reading and writing together:
/// it writes the faces around its region (the cell's vertices and `rings` rings, each edge at
/// most `longest` long), and reads the zone's margin around the cell, the faces within the
/// collision distance and three edges of what it writes (the reference surface and the safety
/// checks), and the faces around the vertices there.
pub(super) fn reach(settings: &RemeshSettings, rings: u32, longest: f32) -> f32 {
    let l = settings.target_edge;
    let writes = (rings as f32 + 2.0) * longest + l;
    let reads = (MARGIN_EDGES * l).max(settings.collision_distance + 3.0 * l) + 2.0 * longest + l;
    writes + reads
}

impl Plan {
    /// Groups `cells` (in the round's order, on a lattice `width` wide shifted by `shift`)
    /// into slabs along the axis they span most, each wide enough that a wave's copies stay
    /// apart; `Err` (the cells back) where that leaves fewer than [`MIN_SLABS`].
    pub(super) fn of(
        cells: Vec<Cell>,
        (width, shift): (f32, f32),
        reach: f32,
        longest: f32,
    ) -> Result<Plan, Vec<Cell>> {
        let Some(axis) = widest_axis(&cells) else {
            return Err(cells);
        };
        // A slab two copies' margins wide, and two edges each side for the faces around their
        // rims, keeps a wave's copies apart.
        let margin = reach + longest;
        let per_slab = ((2.0 * margin + 4.0 * longest) / width).ceil().max(1.0) as i32;
        let slab_of = |cell: &Cell| cell.0[axis].div_euclid(per_slab);
        let mut ids: Vec<i32> = cells.iter().map(slab_of).collect();
        ids.sort_unstable();
        ids.dedup();
        if ids.len() < MIN_SLABS {
            return Err(cells);
        }
        let mut slabs: Vec<Slab> = ids
            .iter()
            .map(|_| Slab {
                cells: Vec::new(),
                span: (f32::INFINITY, f32::NEG_INFINITY),
                near: FxHashSet::default(),
            })
            .collect();
        let around = (margin / width).ceil() as i32;
        for cell in cells {
            let slab = &mut slabs[ids.binary_search(&slab_of(&cell)).expect("listed")];
            slab.span = (
                slab.span.0.min(cell.1.min[axis] - margin),
                slab.span.1.max(cell.1.max[axis] + margin),
            );
            for dz in -around..=around {
                for dy in -around..=around {
                    for dx in -around..=around {
                        slab.near.insert(cell.0 + IVec3::new(dx, dy, dz));
                    }
                }
            }
            slab.cells.push(cell);
        }
        Ok(Plan {
            axis,
            lattice: (width, shift),
            slabs,
        })
    }

    /// The vertices a copy of slab `slab` must hold: those within the margin of its cells.
    fn copied_vertices(&self, mesh: &Mesh, slab: usize) -> Vec<u32> {
        let Slab { span, near, .. } = &self.slabs[slab];
        (0..mesh.vertex_count() as u32)
            .filter(|&v| {
                let p: Vec3 = mesh.positions()[v as usize];
                (span.0..=span.1).contains(&p[self.axis])
                    && mesh.is_vertex_live(v)
                    && near.contains(&cell_of(p, self.lattice))
            })
            .collect()
    }

    /// The two waves' slabs (by index): even, then odd.
    pub(super) fn waves(&self) -> [Vec<usize>; 2] {
        let all = 0..self.slabs.len();
        [
            all.clone().step_by(2).collect(),
            all.skip(1).step_by(2).collect(),
        ]
    }

    /// How many vertices the cells of slab `slab` hold: the measure of its work.
    fn vertex_count(&self, slab: usize) -> usize {
        self.slabs[slab].cells.iter().map(|cell| cell.2.len()).sum()
    }

    /// The cells of slab `slab`.
    pub(super) fn cells_of(&self, slab: usize) -> &[Cell] {
        &self.slabs[slab].cells
    }
}

/// The axis (0 x, 1 y, 2 z) along which the cells' positions spread most.
fn widest_axis(cells: &[Cell]) -> Option<usize> {
    let first = cells.first()?.0;
    let (lo, hi) = cells
        .iter()
        .fold((first, first), |(lo, hi), c| (lo.min(c.0), hi.max(c.0)));
    let spread = hi - lo;
    Some(
        (0..3)
            .max_by_key(|&a| (spread[a], -(a as i32)))
            .expect("three axes"),
    )
}

/// What a slab's copy came back with.
struct Done {
    patch: Patch,
    report: RemeshReport,
    /// The slab's share of the volume budgets, and its bound on edges.
    carried: Carried,
}

/// Remeshes the slabs `wave` of `plan` at once, on as many threads as rayon's pool the caller
/// runs in has, and puts them back. `progress` hears of every cell done, on the caller's
/// thread. `Err` (the mesh as it was) where a copy could not be made or put back; the caller
/// then runs the wave's cells in place.
pub(super) fn run_wave(
    mesh: &mut Mesh,
    (plan, wave): (&Plan, &[usize]),
    carried: &mut Carried,
    round: &Round<'_>,
    progress: &mut dyn FnMut(usize),
) -> Result<RemeshReport, ()> {
    if wave.is_empty() {
        return Ok(RemeshReport::default());
    }
    let threads = rayon::current_num_threads().clamp(1, wave.len());
    // The largest slabs first, so no thread is left with a large one at the end.
    let mut order: Vec<usize> = (0..wave.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(plan.vertex_count(wave[i])));
    let next = AtomicUsize::new(0);
    let (tell, told) = mpsc::channel::<()>();
    let (shared, carried_now): (&Mesh, &Carried) = (mesh, carried);
    let results: Vec<(usize, Option<Done>)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                let (next, order, tell) = (&next, &order, tell.clone());
                scope.spawn(move || {
                    let mut done = Vec::new();
                    // Kept from slab to slab: sized once, emptied in O(1).
                    let mut sets = RemeshSets::default();
                    loop {
                        let Some(&i) = order.get(next.fetch_add(1, Ordering::Relaxed)) else {
                            return done;
                        };
                        let work = (shared, carried_now, wave.len());
                        let slab = run_slab(work, (plan, wave[i]), round, (&mut sets, &tell));
                        done.push((i, slab));
                    }
                })
            })
            .collect();
        drop(tell);
        for () in told {
            progress(1);
        }
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("a slab's worker panicked"))
            .collect()
    });
    let mut done: Vec<Option<Done>> = (0..wave.len()).map(|_| None).collect();
    for (i, result) in results {
        done[i] = result;
    }
    let done: Vec<Done> = done.into_iter().collect::<Option<_>>().ok_or(())?;
    let (patches, rest): (Vec<Patch>, Vec<_>) = done
        .into_iter()
        .map(|d| (d.patch, (d.report, d.carried)))
        .unzip();
    let maps = mesh.put_back(&patches).map_err(|_| ())?;
    let mut report = RemeshReport {
        slabs: wave.len(),
        ..RemeshReport::default()
    };
    for ((done, share), map) in rest.iter().zip(&maps) {
        carried.closed.absorb(&share.closed, map);
        carried.longest = carried.longest.max(share.longest);
        report.add(done);
    }
    Ok(report)
}

/// One slab's cells remeshed in a copy of the mesh around it (of `ways` slabs run at once),
/// with the thread's sets; `None` where no copy could be made. `tell` hears of each cell done.
fn run_slab(
    (mesh, carried, ways): (&Mesh, &Carried, usize),
    (plan, slab): (&Plan, usize),
    round: &Round<'_>,
    (sets, tell): (&mut RemeshSets, &mpsc::Sender<()>),
) -> Option<Done> {
    let inside = plan.copied_vertices(mesh, slab);
    let mut patch = mesh.copy_patch(&inside).ok()?;
    let mut share = Carried {
        closed: carried.closed.share(&patch.sources, ways),
        longest: carried.longest,
    };
    let mut grid = SpatialHash::build(&patch.mesh, round.grid_cell).ok()?;
    let cells: Vec<(&Aabb, Vec<u32>)> = (plan.cells_of(slab).iter())
        .map(|(_, core, seeds)| {
            (
                core,
                seeds.iter().filter_map(|&v| patch.copy_of(v)).collect(),
            )
        })
        .collect();
    // The caller may have stopped listening only by panicking.
    let mut done = || {
        let _ = tell.send(());
    };
    let copy = (&mut patch.mesh, &mut grid);
    let report = remesh_cells(
        copy,
        cells.into_iter(),
        (sets, &mut share),
        round,
        &mut done,
    );
    Some(Done {
        patch,
        report,
        carried: share,
    })
}
