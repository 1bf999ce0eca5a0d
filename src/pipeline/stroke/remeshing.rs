//! Remeshing during and after a stroke (as `PipelineSettings::remeshing` says, and a grab's
//! between its samples where it stretched the surface), the fuse layers' topology pass after
//! it, and the running bound on edge lengths both leave behind.

use std::collections::HashMap;
use std::time::Instant;

use super::{Active, SamplesReport};
use crate::mesh::Mesh;
use crate::pipeline::Remeshing;
use crate::pipeline::engine::{fuse_touched, longest_edge_at, millis, remesh_touched};
use crate::pipeline::kernels::StepKernels;
use crate::remesh::RemeshReport;

impl Active {
    /// [`Remeshing::AfterSample`]: remeshes around `moved`, what the last sample moved (a
    /// grab keeps moving what it caught, so its region is remeshed once, after the stroke).
    pub(super) fn remesh_after_sample(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &mut Mesh,
        moved: &[u32],
        call: &mut SamplesReport,
    ) {
        let started = Instant::now();
        let (pass, changed) = self.remesh_around(kernels, mesh, moved);
        self.remeshed.extend_from_slice(&changed);
        self.scratch.size_for(mesh);
        call.changed.extend_from_slice(&changed);
        call.topology_changed |= pass.splits + pass.collapses + pass.flips > 0;
        call.phases.remesh += millis(started);
    }

    /// A grab stretches the surface between what it caught and what it left behind. Remeshed
    /// only at the stroke's end, a long drag leaves edges many times `L` whose splitting
    /// compounds (slivers split into slivers: a drag of 10 units over a 2K-face sphere spent
    /// 4.9 s on 15K splits and 12K collapses). Remeshing around the moved vertices whenever
    /// their faces hold an edge over [`GRAB_STRETCH`]·`L` keeps each remesh local and the
    /// drag's cost linear in its length. Remeshing between samples adds vertices the grab did
    /// not catch: [`regrab`] decides which join it.
    pub(super) fn remesh_stretched_grab(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &mut Mesh,
        moved: &[u32],
        call: &mut SamplesReport,
    ) {
        let bound = GRAB_STRETCH * self.lengths.edge;
        let faces = faces_around(mesh, moved.iter().copied());
        if !self.left_long.any_due(mesh, &faces, bound) {
            return;
        }
        let first_new = mesh.vertex_count() as u32;
        self.remesh_after_sample(kernels, mesh, moved, call);
        for captured in [&mut self.captured, &mut self.captured_image]
            .into_iter()
            .flatten()
        {
            regrab(mesh, captured, first_new);
        }
        let live = moved.iter().copied().filter(|&v| mesh.is_vertex_live(v));
        let faces = faces_around(mesh, live.chain(first_new..mesh.vertex_count() as u32));
        self.left_long.record(mesh, &faces, bound);
        if self.lets_go() {
            self.let_go.let_go_of(self.left_long.ends());
        }
    }

    /// After the stroke (as `remeshing` says): remeshes every vertex the stroke moved, and
    /// returns the vertices remeshing changed.
    pub(super) fn remesh_after_stroke(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &mut Mesh,
        remeshing: Remeshing,
    ) -> Vec<u32> {
        self.touched_list.sort_unstable();
        self.report.touched = self.touched_list.len();
        let remesh_now = match remeshing {
            Remeshing::Off => false,
            Remeshing::AfterStroke => true,
            Remeshing::AfterSample => self.stroke.brush.kind.drags(),
        };
        if !remesh_now {
            return Vec::new();
        }
        let started = Instant::now();
        let seeds = std::mem::take(&mut self.touched_list);
        let (_, changed) = self.remesh_around(kernels, mesh, &seeds);
        self.touched_list = seeds;
        self.report.phases.remesh += millis(started);
        changed
    }

    /// Remeshes around `seeds` with the stroke's lengths, what is left of its bound on new
    /// faces and its culling, and books the pass in the stroke's report and edge bound.
    fn remesh_around(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &mut Mesh,
        seeds: &[u32],
    ) -> (RemeshReport, Vec<u32>) {
        let lengths = (
            self.lengths.edge,
            self.lengths.collision_distance,
            self.prepared.ring,
            self.splits_left,
        );
        let culling = self.cull.then_some(self.prepared.max_edge);
        let (pass, changed) = remesh_touched(
            mesh,
            (&mut self.prepared.grid, kernels, &mut self.scratch.remesh),
            (seeds, culling),
            lengths,
        );
        self.prepared.max_edge = self.prepared.max_edge.max(pass.longest_edge);
        self.splits_left -= pass.splits;
        self.report.remesh.add(&pass);
        (pass, changed)
    }

    /// Joins and splits the stroke's fuse layers where it left them touching themselves
    /// (`crate::topology`), over what it moved and what remeshing changed; adds the vertices
    /// that changed to `remeshed`.
    pub(super) fn fuse_after_stroke(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &mut Mesh,
        remeshed: &mut Vec<u32>,
    ) {
        let seeds: Vec<u32> = (self.touched_list.iter().chain(&self.remeshed))
            .chain(remeshed.iter())
            .copied()
            .collect();
        let lengths = (
            self.lengths.edge,
            self.lengths.collision_distance,
            self.prepared.ring,
        );
        let grid = &mut self.prepared.grid;
        self.report.topology =
            fuse_touched(mesh, (grid, kernels), (&self.stroke.fuse, &seeds), lengths);
        remeshed.extend_from_slice(&self.report.topology.changed);
    }

    /// The running edge bound only grows during a stroke (a grab stretches edges that its
    /// remeshing then splits). At the end, every edge the stroke changed has an end it moved
    /// or remeshing changed, and every other edge is as it was, within the bound the stroke
    /// began with: the bound becomes the larger of that and the longest changed edge. Without
    /// this, a grab's passing stretch would stay in the bound until a rescan of the whole mesh.
    pub(super) fn tighten_edge_bound(&mut self, mesh: &Mesh, remeshed_at_end: &[u32]) {
        let changed: Vec<u32> = (self.touched_list.iter())
            .chain(&self.remeshed)
            .chain(remeshed_at_end)
            .copied()
            .filter(|&v| mesh.is_vertex_live(v))
            .collect();
        let longest = longest_edge_at(mesh, &changed);
        self.prepared.max_edge = self.edge_bound_at_start.max(longest);
    }
}

/// A grab is remeshed during its stroke once an edge around what it moved is longer than
/// this many `L` (the remesher splits above 4/3·`L`, so each remesh halves such edges about
/// once: the work stays local).
const GRAB_STRETCH: f32 = 2.0;

/// The live faces around `vertices`, ascending, each once.
fn faces_around(mesh: &Mesh, vertices: impl Iterator<Item = u32>) -> Vec<u32> {
    let mut faces: Vec<u32> = vertices.flat_map(|v| mesh.faces_around(v)).collect();
    faces.sort_unstable();
    faces.dedup();
    faces
}

/// How much an edge that remeshing left over the stretch bound must grow before remeshing
/// tries it again.
const REGROWTH: f32 = 1.25;

/// The edges around a grab that its last remesh left longer than the stretch bound (a split
/// that would put a vertex within the collision distance of the needle's other side is
/// refused), with their length then. Without it every later sample remeshed the grab's whole
/// region again to refuse the same splits: a drag of 100 units over a 2K-face sphere ran
/// 2,208 remeshes that refused 246K edits (5.7 s), and now 120 that refuse 8.6K. Such an edge
/// is tried again once it has grown by [`REGROWTH`], so a needle drawn out evenly is retried
/// a number of times logarithmic in its length.
#[derive(Debug, Default)]
pub(super) struct LeftLong {
    lengths: HashMap<(u32, u32), f32>,
}

impl LeftLong {
    /// Whether `faces` hold an edge over `bound` that the last remesh did not leave, or one
    /// it left that has grown by [`REGROWTH`] since.
    fn any_due(&self, mesh: &Mesh, faces: &[u32], bound: f32) -> bool {
        let mut due = false;
        for_each_long_edge(mesh, faces, bound, |edge, length| {
            due |= self
                .lengths
                .get(&edge)
                .is_none_or(|&was| length > was * REGROWTH);
        });
        due
    }

    /// The ends of the edges kept.
    fn ends(&self) -> impl Iterator<Item = u32> + '_ {
        self.lengths.keys().flat_map(|&(a, b)| [a, b])
    }

    /// Keeps the edges of `faces` over `bound`, as remeshing left them.
    fn record(&mut self, mesh: &Mesh, faces: &[u32], bound: f32) {
        self.lengths.clear();
        for_each_long_edge(mesh, faces, bound, |edge, length| {
            self.lengths.insert(edge, length);
        });
    }
}

/// Calls `found` with each edge of `faces` longer than `bound` (its ends in ascending order)
/// and its length; an edge two faces share comes twice.
fn for_each_long_edge(
    mesh: &Mesh,
    faces: &[u32],
    bound: f32,
    mut found: impl FnMut((u32, u32), f32),
) {
    let positions = mesh.positions();
    for &f in faces {
        let corners = mesh.faces()[f as usize];
        for (a, b) in [(0, 1), (1, 2), (2, 0)].map(|(i, j)| (corners[i], corners[j])) {
            let length = positions[a as usize].distance(positions[b as usize]);
            if length > bound {
                found((a.min(b), a.max(b)), length);
            }
        }
    }
}

/// The grab's caught vertices after remeshing between its samples: those remeshing removed
/// leave; each vertex it added (numbered from `first_new` on) joins with the smallest weight
/// among its caught neighbours, and only when all its earlier neighbours were caught — so a
/// vertex split between the grab and the surface it left stays with the surface (the drag
/// extrudes instead of stretching every edge again), and none moves ahead of its
/// neighbours. Deterministic: the new vertices are taken in index order.
fn regrab(mesh: &Mesh, captured: &mut Vec<(u32, f32)>, first_new: u32) {
    captured.retain(|&(v, _)| !mesh.is_vertex_dead(v));
    let mut weight_of: HashMap<u32, f32> = captured.iter().copied().collect();
    for v in first_new..mesh.vertex_count() as u32 {
        if mesh.is_vertex_dead(v) {
            continue;
        }
        // Neighbours added after `v` have no weight yet and do not vote.
        let weight = mesh
            .neighbours(v)
            .into_iter()
            .filter(|&n| n < v)
            .map(|n| weight_of.get(&n).copied().unwrap_or(0.0))
            .fold(f32::INFINITY, f32::min);
        if weight.is_finite() && weight > 0.0 {
            weight_of.insert(v, weight);
            captured.push((v, weight));
        }
    }
}
