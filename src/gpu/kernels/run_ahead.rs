//! A stroke's samples recorded ahead, several in one submission. The pipeline tells the
//! kernels the samples it will ask for ([`StepKernels::upcoming`]); at a sample's start the
//! kernels record that sample and the next ones one after another — each one's selection,
//! brush frame, deformation, moving entries, proximity passes, backstop filter, the normals
//! its moves turned (`moved_normals`) and the filing of its moved vertices in the hash table's
//! overlay (`overlay_members`, then the overlay rebuilt from its slots), each reading the
//! positions, normals and table the one before left on the GPU — copy each one's results
//! aside, and read them all back in one map. The pipeline then takes them one by one as if each
//! had been a submission of its own. Because each sample files what it moved, every sample of a
//! run queries the table with the first one's drift, however long the run.
//!
//! What the GPU ran is what the pipeline would have asked for only while its predictions
//! hold. Those the GPU can see are checked there, by the run's gate (`longest_move`,
//! `sample_gate`, with `moved_edges` after each sample): each sample's selection within the
//! guessed list, its rings within their room, its longest move within the one its passes were
//! sized for, and the edges the samples before it left within the bound they were sized for.
//! The first sample where one fails stops the run before it moves anything, and the samples
//! after it select nothing; the pipeline takes the samples before it and goes on one
//! submission per step from there. The host checks the move and the edges again in its own
//! arithmetic when the pipeline reaches a sample, and the exact backstop's verdict when the
//! pipeline reports the sample's moves (it must undo nothing). From the first sample where one
//! of those fails, the rest are dropped: the rows they wrote go back to the mesh's (positions,
//! and the normals around them).
//!
//! [`StepKernels::upcoming`]: crate::pipeline::StepKernels::upcoming

use std::collections::VecDeque;

use glam::Vec3;

use super::{
    AheadBounds, ClampedAhead, GpuKernels, Resident, SampleLayout, SelectedVertex, StrokeState,
    TableUse, cell_size, in_vertex_order, permuted, record_sample, selection_guess,
};
use crate::gpu::reusable::Patches;
use crate::gpu::{
    GateStatus, GpuContext, GpuError, record_moved_edges, record_moved_normals, ring_bytes,
};
use crate::mesh::Mesh;
use crate::pipeline::step::longest_move;
use crate::pipeline::{Deformed, FrameSource, SampleProbe};

/// At most this many samples in one submission: the read-back grows with each, and each later
/// sample's passes are sized for edges grown by [`EDGE_GROWTH_AHEAD`] per sample before it, so
/// their reach grows with the run. A run starts at two samples and doubles after every run
/// taken whole; a run cut short makes the next one as long as what was taken of it (at least
/// two). A run the gate stops still has the GPU go through the recorded passes of every sample
/// after the stop, emptied but dispatched: starting every run at the rest of the stroke read
/// the run-ahead test back twice instead of 4 times, but in 19–26 s of lavapipe against 15–21
/// s, and on a hardware GPU, where each dispatch has a fixed cost, a 32-sample run stopped early
/// would waste hundreds of them (in the 100K-face plaster bench 1 sample in 7 takes several
/// steps or has a move undone by the exact backstop, and either ends a run).
pub(super) const MAX_SAMPLES_AHEAD: usize = 32;
const FIRST_SAMPLES_AHEAD: usize = 2;

/// A run's later samples assume the mesh's longest edge grows by at most this share of the
/// assumed move per sample before them; the gate stops the run at the first whose edges, as
/// `moved_edges` measured them, say otherwise (and the host drops it should the pipeline's own
/// bound disagree). A step lengthens an edge by at most twice its longest move, but the
/// passes' reach grows with the edge bound (their work with its cube): plaster at 2K faces,
/// steps of a cell, grew its longest edge by 0 to 0.32 of the step limit a sample; assuming the
/// worst case (2) made a run of four samples cost three times one assuming this share. With the
/// gate, 0.25 stopped the run-ahead test's runs once more for the same lavapipe time.
const EDGE_GROWTH_AHEAD: f32 = 0.5;

/// A sample recorded ahead, waiting for the pipeline to reach it.
pub(super) struct QueuedSample {
    /// Where it is in the plan, and the probe the pipeline will ask with.
    index: usize,
    probe: SampleProbe,
    deformed: Deformed,
    /// The step's passes; `None` when nothing was selected.
    ahead: Option<ClampedAhead>,
    /// The longest move the passes were sized for.
    assumed_move: f32,
    /// The bound on the mesh's edges at the sample's start the passes were sized for.
    max_edge: f32,
    /// Its moved vertices were filed in the overlay on the GPU (every sample of a run but the
    /// last).
    filed: bool,
}

/// The vertices a queued sample's passes may have moved.
fn moved_by(sample: &QueuedSample) -> &[u32] {
    sample.ahead.as_ref().map_or(&[], |a| a.vertices.as_slice())
}

impl GpuKernels {
    /// Where the sample the pipeline starts with `probe` is in the plan, looking from the
    /// sample after the last one taken ahead; `None` when it is not planned or is the last.
    pub(super) fn planned(&self, probe: &SampleProbe) -> Option<usize> {
        let from = self.plan_next.min(self.plan.len());
        self.plan[from..]
            .iter()
            .position(|p| p == probe)
            .map(|at| from + at)
            .filter(|&at| at + 1 < self.plan.len())
    }

    /// Records the planned samples from `from` on in one submission (as many as the run's
    /// length, at most [`MAX_SAMPLES_AHEAD`]; nothing when that is fewer than two) and queues
    /// what each left for the pipeline. The passes are sized as a single step's would be
    /// (`assumed_move`: twice the last move, within `limit`), each later sample's from edges
    /// grown by [`EDGE_GROWTH_AHEAD`] of that move per sample before it.
    pub(super) fn gpu_run_ahead(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        from: usize,
        limit: f32,
    ) -> Result<(), GpuError> {
        self.check_injected_failure()?;
        self.check_gpu_filing(mesh);
        self.drop_all_ahead(mesh);
        let filter = self.backstop_on_gpu;
        let assumed_move = self.assumed_move(limit);
        let (gpu, step, readback) = (&self.gpu, &mut self.step, &mut self.readback);
        let r = GpuKernels::prepare(
            gpu,
            (&mut self.resident, &mut self.uploads),
            mesh,
            cell_size(state),
            TableUse::Proximity,
        )?;
        let capacity = r.selection.capacity;
        let guess = selection_guess(self.last_selection, capacity);
        // Each sample's moved vertices are filed in the overlay on the GPU before the next
        // (`Hashed::record_gpu_filing`): every sample queries with the drift of the first.
        let drift = r.hashed().drift;
        let count = (self.plan.len() - from).min(
            self.run_length
                .clamp(FIRST_SAMPLES_AHEAD, MAX_SAMPLES_AHEAD),
        );
        if count < 2 || ring_bytes(guess) > gpu.limits.max_storage_buffer_binding_size {
            return Ok(());
        }
        step.reserve_sample(gpu, (r, mesh), guess, true, true, filter)?;
        // Room for the overlay's members and for every slot of the moving lists of the samples
        // that file theirs (all but the last); no more than the vertices there are.
        let room = (r.hashed().overlay.as_ref().map_or(0, |o| o.members.len())
            + (count - 1) * guess)
            .min(r.vertices.count);
        let Some(hashed) = &mut r.hashed else {
            unreachable!("prepare built the hash table");
        };
        hashed.start_gpu_filing(gpu, room)?;
        let r = &*r;
        let Some(topology) = &r.topology else {
            unreachable!("reserve_sample made the topology resident");
        };
        let list_bytes = (guess * std::mem::size_of::<SelectedVertex>()) as u64;
        let mut encoder = gpu.encoder("samples ahead");
        r.hashed().record_gpu_table(gpu, &mut encoder)?;
        // The gate's edge bound starts at the pipeline's; each sample but the last grows it by
        // the faces it turned (`moved_edges`) for the next one's verdict.
        step.start_gate(gpu, state.max_edge);
        // The edges as the samples before sample j may have lengthened them (checked by the
        // gate, and by the host when the pipeline reaches it).
        let edge_bound = |j: usize| state.max_edge + EDGE_GROWTH_AHEAD * j as f32 * assumed_move;
        let mut layout = None;
        let mut sample_bytes = 0;
        for j in 0..count {
            let (dab, normal) = self.plan[from + j];
            let state = StrokeState {
                max_edge: edge_bound(j),
                ..*state
            };
            let recorded = record_sample(
                gpu,
                &mut encoder,
                (r, step),
                &state,
                &dab,
                (FrameSource::Selection { normal }, true),
                guess,
                Some(AheadBounds {
                    assumed_move,
                    drift,
                }),
                filter,
            )?;
            record_moved_normals(
                gpu,
                &mut encoder,
                (&r.vertices.positions, &topology.buffer),
                topology.layout.vertex_rows_base,
                (step.moving.buffer(), guess),
                &r.normals,
            )?;
            if j + 1 < count {
                record_moved_edges(
                    gpu,
                    &mut encoder,
                    (&r.vertices.positions, &topology.buffer),
                    topology.layout.vertex_rows_base,
                    (step.moving.buffer(), guess),
                    &step.gate_status,
                )?;
                r.hashed().record_gpu_filing(
                    gpu,
                    &mut encoder,
                    &r.vertices.positions,
                    (step.moving.buffer(), guess),
                )?;
            }
            let mut parts = vec![(&r.selection.count, 4), (&r.selection.selected, list_bytes)];
            parts.extend_from_slice(&recorded.parts);
            if j == 0 {
                // Every sample leaves the same parts.
                sample_bytes = parts.iter().map(|&(_, bytes)| bytes).sum::<u64>();
                readback.reserve(gpu, sample_bytes * count as u64)?;
                layout = Some(recorded.layout);
            }
            readback.record_copies(&mut encoder, &parts, j as u64 * sample_bytes);
        }
        let data = readback.submit_and_map(gpu, encoder, sample_bytes * count as u64)?;
        let layout: SampleLayout = layout.expect("at least two samples recorded");
        self.uploads.batches += 1;
        self.run_taken = 0;

        // What the GPU filed, for the host's next filing to hold too.
        let mut filed_on_gpu = Vec::new();
        for (j, bytes) in data.chunks_exact(sample_bytes as usize).enumerate() {
            let found = (u32::from_le_bytes(bytes[..4].try_into().expect("four bytes")) as usize)
                .min(capacity);
            self.last_selection = self.last_selection.max(found);
            let head = found.min(guess);
            let list: Vec<SelectedVertex> = bytemuck::pod_collect_to_vec(&bytes[4..4 + 8 * head]);
            let (dab, normal) = self.plan[from + j];
            let parts = layout.split(&bytes[4 + list_bytes as usize..], &dab);
            let status = parts.gate.expect("runs go through the gate");
            if status.stopped != 0 {
                // The gate stopped the run at this sample, before it moved anything, and the
                // samples after it selected nothing: there is nothing to put back.
                self.run_length = j.max(FIRST_SAMPLES_AHEAD);
                self.uploads.gated_ahead += 1;
                self.after_stop(from + j, status, limit);
                break;
            }
            let (order, selection) = in_vertex_order(&list);
            if j + 1 < count {
                filed_on_gpu.extend(list.iter().map(|s| s.vertex));
            }
            // The gate stops a run on a cut list or cut rings (the same count and buffer).
            debug_assert!(found <= guess && parts.ring_overflows == Some(0));
            let ahead = (!selection.is_empty()).then(|| {
                let targets: Vec<Vec3> = permuted(
                    &order,
                    &bytemuck::pod_collect_to_vec(&parts.targets[..found * 12]),
                );
                let clamp = layout.clamp.expect("passes recorded");
                let (finals, backstop) = step.parse_clamp(parts.clamp, guess, clamp);
                ClampedAhead {
                    vertices: selection.iter().map(|&(v, _)| v).collect(),
                    targets,
                    finals: permuted(&order, &finals),
                    backstop,
                }
            });
            self.queued.push_back(QueuedSample {
                index: from + j,
                probe: (dab, normal),
                deformed: Deformed {
                    targets: ahead.as_ref().map(|a| a.targets.clone()),
                    selection,
                    frame: parts.frame,
                    deform_millis: 0.0,
                },
                ahead,
                assumed_move,
                max_edge: edge_bound(j),
                filed: j + 1 < count,
            });
        }
        if let Some(hashed) = self.resident.as_mut().and_then(|r| r.hashed.as_mut()) {
            hashed.moved.extend_from_slice(&filed_on_gpu);
        }
        Ok(())
    }

    /// After the gate stopped a run at planned sample `index`: whether the pipeline's call for
    /// it starts the next run. One whose selection outgrew the guessed list, whose edges the
    /// samples before grew past the prediction, or whose move outgrew the assumed one within a
    /// step does, sized from what this run read (the list's count, the pipeline's edges, the
    /// move: `last_move`). One that moves farther than a step (several steps), or whose rings
    /// outgrow their fixed room, would stop it again: the pipeline takes it one submission per
    /// step, and the sample after it starts the next run.
    fn after_stop(&mut self, index: usize, status: GateStatus, limit: f32) {
        let longest = status.longest_move();
        let moved_too_far = status.stopped & GateStatus::MOVE != 0;
        if moved_too_far && longest.is_finite() {
            self.last_move = longest;
        }
        // A NaN move is not within the limit either.
        let one_step = longest <= limit;
        if status.stopped & GateStatus::RINGS != 0 || (moved_too_far && !one_step) {
            self.plan_next = index + 1;
        }
    }

    /// The queued sample the pipeline starts with `probe`, when it is the next one queued and
    /// its moves are one step within what its passes assumed, from where the mesh is now, and
    /// the pipeline's bound on the edges (`max_edge`) within theirs. Any other probe, or moves
    /// or edges past the assumption, drop the queue.
    /// A sample dropped for moving too far is not run ahead again: the pipeline takes it one
    /// submission per step, and the next sample starts a new run sized from its move.
    pub(super) fn take_queued(
        &mut self,
        mesh: &Mesh,
        probe: &SampleProbe,
        max_edge: f32,
    ) -> Option<Deformed> {
        if self.failed.is_some() {
            self.queued.clear();
            return None;
        }
        let head = self.queued.front()?;
        // A NaN bound does not fit either.
        let edges_fit = max_edge <= head.max_edge;
        if head.probe != *probe || !edges_fit {
            self.drop_queued(mesh);
            return None;
        }
        let longest = head
            .ahead
            .as_ref()
            .map(|ahead| longest_move(mesh, &head.deformed.selection, &ahead.targets));
        self.plan_next = self.plan_next.max(head.index + 1);
        if let Some(longest) = longest {
            self.last_move = longest;
            // A NaN move does not fit either.
            let fits = longest <= head.assumed_move;
            if !fits {
                self.drop_queued(mesh);
                return None;
            }
        }
        let sample = self.queued.pop_front()?;
        self.run_taken += 1;
        if self.queued.is_empty() {
            // The whole run was taken as predicted.
            self.run_length = (2 * self.run_taken).min(MAX_SAMPLES_AHEAD);
        }
        self.uploads.samples_ahead += 1;
        self.ahead = sample.ahead;
        self.taken_filed = sample.filed;
        Some(sample.deformed)
    }

    /// Drops every queued sample: the rows their passes wrote go back to the mesh's.
    pub(super) fn drop_queued(&mut self, mesh: &Mesh) {
        let queued = std::mem::take(&mut self.queued);
        if !queued.is_empty() {
            self.run_length = self.run_taken.max(FIRST_SAMPLES_AHEAD);
        }
        let mut vertices: Vec<u32> = queued.iter().flat_map(moved_by).copied().collect();
        if vertices.is_empty() {
            return;
        }
        vertices.sort_unstable();
        vertices.dedup();
        self.uploads.dropped_ahead += queued.iter().filter(|s| s.ahead.is_some()).count();
        if let Some(hashed) = self.resident.as_mut().and_then(|r| r.hashed.as_mut()) {
            // Filed where the dropped samples put them.
            hashed.gpu_drift = None;
        }
        put_back_rows(&self.gpu, self.resident.as_ref(), mesh, &vertices);
    }

    /// After the pipeline reported a step's moves: when they are not what the passes ran ahead
    /// left (the exact backstop undid some), the samples queued after were recorded on the
    /// wrong positions and are dropped.
    pub(super) fn check_taken(&mut self, mesh: &Mesh) {
        let Some((vertices, finals)) = self.taken.take() else {
            return;
        };
        let positions = mesh.positions();
        let as_predicted = vertices
            .iter()
            .zip(&finals)
            .all(|(&v, &p)| positions[v as usize] == p);
        if !as_predicted {
            self.drop_queued(mesh);
        }
    }
}

/// Puts the GPU's rows of `vertices` — positions, and the normals of every corner of the faces
/// around them, which `moved_normals` may have rewritten — back to the mesh's, in one upload.
pub(super) fn put_back_rows(
    gpu: &GpuContext,
    resident: Option<&Resident>,
    mesh: &Mesh,
    vertices: &[u32],
) {
    let Some(r) = resident else {
        return;
    };
    let mut corners: Vec<u32> = vertices
        .iter()
        .flat_map(|&v| mesh.faces_around(v).flat_map(|f| mesh.faces()[f as usize]))
        .collect();
    corners.sort_unstable();
    corners.dedup();
    let mut patches = Patches::default();
    patches.rows(&r.vertices.positions, mesh.positions(), vertices);
    patches.rows(&r.normals, mesh.normals(), &corners);
    patches.submit(gpu);
}

/// The queue of samples recorded ahead, oldest first.
pub(super) type Queue = VecDeque<QueuedSample>;
