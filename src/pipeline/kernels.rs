//! The seam between Algorithm 2's control flow and where its data-parallel steps run. The
//! pipeline ([`super::Pipeline`]) owns the loop — samples, steps, the exact backstop, remeshing — and
//! asks its kernels to select, deform and clamp moves (the proximity passes): on the CPU
//! ([`CpuKernels`]) or through the WGSL kernels ([`crate::gpu::GpuKernels`]). One loop for both keeps their results
//! comparable vertex for vertex, which is what the parity figures of `bench --backend both`
//! measure.

use std::time::Instant;

use glam::Vec3;

use super::step::{brush_frame, deform, select};
use crate::abi::GateStatus;
use crate::brush::{Dab, DabFrame};
use crate::collide::{Backstop, Region, StepMoves, StrokeState, clamp_in_region};
use crate::mesh::{Mesh, MeshVersion};
use serde::Serialize;

/// Selection and deformation of one brush step.
pub trait StepKernels: Send {
    /// For reports: "cpu", or the GPU adapter's name.
    fn name(&self) -> String;
    /// Whether [`StepKernels::clamp`] runs off the CPU (for reports).
    fn collides_on_gpu(&self) -> bool {
        false
    }
    /// Why these kernels gave up and fell back to the CPU, if they did.
    fn failure(&self) -> Option<String> {
        None
    }
    /// Gets ready for strokes on `mesh` with the pipeline's cells of `cell_size` (the GPU's:
    /// its copy of the mesh uploaded, its hash table built), so that the first stroke does not
    /// pay for it. Called before every stroke; nothing to do when ready.
    fn warm_up(&mut self, _mesh: &Mesh, _cell_size: f32) {}
    /// The vertices under the brush with their falloff weights, in vertex order.
    fn select(&mut self, state: &StrokeState<'_>, mesh: &Mesh, dab: &Dab) -> Vec<(u32, f32)>;
    /// The selection under `dab` with, for a deforming brush, where `dab` moves each selected
    /// vertex: at a sample's start with the brush frame taken from the selection
    /// ([`FrameSource::Selection`], [`brush_frame`]), at its later steps under the dab's own.
    /// The GPU does it all in one submission.
    fn select_and_deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        (source, deforms): (FrameSource, bool),
    ) -> Deformed {
        let selection = self.select(state, mesh, dab);
        let frame = match source {
            FrameSource::Selection { normal } => brush_frame(mesh, &selection, dab, normal),
            FrameSource::Dab => dab.frame,
        };
        let dab = Dab { frame, ..*dab };
        let started = Instant::now();
        let targets = (deforms && !selection.is_empty())
            .then(|| self.deform(state, mesh, &dab, &selection, None));
        Deformed {
            selection,
            frame,
            targets,
            deform_millis: started.elapsed().as_secs_f64() * 1e3,
        }
    }
    /// [`StepKernels::select_and_deform`] for a deforming brush, and, from kernels that run
    /// the proximity passes ([`StepKernels::collides_on_gpu`]), the step's passes and backstop
    /// filter in the same submission, on the assumption that the moves make one step of at most
    /// `step_limit` ([`steps_for`](super::step::steps_for) gives 1): the pipeline's [`StepKernels::clamp`] of exactly
    /// these moves then takes that result instead of running the passes. Where the assumption
    /// fails the kernels drop the result, and clamp whatever moves the pipeline settles on.
    /// `at` says which sample or step of the stroke this is.
    fn select_deform_and_clamp(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        (source, _at): (FrameSource, CallAt),
        _step_limit: f32,
    ) -> Deformed {
        self.select_and_deform(state, mesh, dab, (source, true))
    }
    /// The samples numbered `first..` of the stroke that the pipeline is about to run, in
    /// order, each as it will pass it to [`StepKernels::select_deform_and_clamp`] at the
    /// sample's start; what was given before is void. Empty when no more follow (the stroke
    /// begins or ends, or its samples are not to be run ahead). Kernels that can (the GPU's)
    /// record several of them in one submission, and answer the pipeline's calls for them
    /// from it, knowing each call by its [`CallAt`].
    fn given(&mut self, _mesh: &Mesh, _first: usize, _probes: &[SampleProbe]) {}
    /// Where the brush moves each selected vertex: for step `at` of a sample, or (`None`) for
    /// the whole move of a sample.
    fn deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        selection: &[(u32, f32)],
        at: Option<CallAt>,
    ) -> Vec<Vec3>;
    /// The collision response's first phase, [`crate::collide::clamp_moves`]: the selection
    /// moved to its targets, then pulled back where it comes too close to a face. `before`
    /// holds each selected vertex's start; `region` is the step's, gathered here if needed.
    /// Leaves the positions in `mesh`, and says what it leaves the exact backstop.
    fn clamp(
        &mut self,
        state: &StrokeState<'_>,
        region: &mut Region,
        mesh: &mut Mesh,
        moves: StepMoves<'_>,
        before: &[Vec3],
    ) -> Backstop {
        clamp_in_region(state, region, mesh, moves, before)
    }
    /// The pipeline has finished moving `vertices` (ascending; each by at most `max_move` since
    /// the kernels last saw it): kernels that keep a copy of the positions bring it up to date.
    fn moved(&mut self, _mesh: &Mesh, _vertices: &[u32], _max_move: f32) {}
    /// The pipeline recomputed the normals of `vertices` (ascending).
    fn normals_changed(&mut self, _mesh: &Mesh, _vertices: &[u32]) {}
    /// Remeshing changed `mesh` from version `since`: `changed` (ascending) lists every vertex
    /// whose position, normal, flags, faces or neighbours changed, vertices it added included.
    fn remeshed(&mut self, _mesh: &Mesh, _since: MeshVersion, _changed: &[u32]) {}
    /// How the kernels' copy of the mesh was kept up to date (for reports and tests); `None`
    /// for kernels that keep none.
    fn uploads(&self) -> Option<Uploads> {
        None
    }
    /// How the kernels filtered the exact backstop's first rounds, for kernels that do.
    fn backstop_filter(&self) -> Option<BackstopFilter> {
        None
    }
    /// What the kernels hold in GPU memory now, with `mesh` their copy; `None` for kernels
    /// that hold none.
    fn gpu_memory(&self, _mesh: &Mesh) -> Option<GpuMemory> {
        None
    }
    /// Compares the kernels' copy of the mesh, if they keep one, with `mesh`: `Err` names the
    /// first difference. Reads everything back: for tests.
    fn check_copy(&self, _mesh: &Mesh) -> Result<(), String> {
        Ok(())
    }
    /// Drops any copy of the mesh the kernels keep ([`super::Pipeline::forget_mesh`]).
    fn forget_mesh(&mut self) {}
    /// The kernels' own position and normal buffers, brought up to date with `mesh` first,
    /// for a renderer on their device to draw from; `None` for kernels that keep no copy on a
    /// GPU, or gave theirs up.
    fn vertex_buffers(&mut self, _mesh: &Mesh) -> Option<EngineVertices> {
        None
    }
}

/// The GPU backend's per-vertex positions and normals (x, y, z each, packed, `count` rows of
/// them current): what the app's viewport draws from when it shares the backend's device.
/// Until the next call says otherwise they follow the engine's work as it is submitted, so a
/// renderer on the same queue sees every step the engine recorded before its own draw.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EngineVertices {
    pub positions: wgpu::Buffer,
    pub normals: wgpu::Buffer,
    pub count: usize,
}

/// Which call of a stroke the pipeline makes, by the number of its sample in the stroke
/// (counting from 0 across [`StrokeInProgress::add_samples`](super::StrokeInProgress::add_samples)
/// calls): kernels that recorded given samples ahead ([`StepKernels::given`]) know the call
/// they recorded by this, never by comparing dabs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CallAt {
    /// A sample's start: its selection, brush frame and whole move.
    Start { sample: usize },
    /// Step `k` of the `steps` a sample takes.
    Step {
        sample: usize,
        k: usize,
        steps: usize,
    },
}

/// A sample's start as the pipeline asks for it: the probe dab (the frame still to be taken
/// from the selection) and the sample's own normal, if any.
pub type SampleProbe = (Dab, Option<Vec3>);

/// Where [`StepKernels::select_and_deform`] takes the brush frame from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrameSource {
    /// The selection (a sample's start): the falloff-weighted normal, unless the sample brings
    /// its own `normal`, and centroid under the brush.
    Selection { normal: Option<Vec3> },
    /// The dab's frame as given (a sample's later steps).
    Dab,
}

/// What [`StepKernels::select_and_deform`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct Deformed {
    /// In vertex order.
    pub selection: Vec<(u32, f32)>,
    pub frame: DabFrame,
    /// One per selection entry; `None` for brushes that do not deform, or nothing selected.
    pub targets: Option<Vec<Vec3>>,
    /// Of the call's time, how much went to the deformation, where it ran apart (booked under
    /// deformation); zero where one submission did everything (booked under selection).
    pub deform_millis: f64,
}

/// How often kernels that keep a copy of the mesh (the GPU's) sent it whole, how often they
/// patched it after remeshing instead, how often they rebuilt their hash table, and how often
/// the CPU waited for them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Uploads {
    pub whole: usize,
    pub patched: usize,
    /// Hash tables built over every vertex (drift past a limit rebuilds).
    pub table_builds: usize,
    /// Times the vertices remeshing changed went into the table's small overlay instead of a
    /// rebuild.
    pub overlay_filings: usize,
    /// Submissions of recorded GPU work, and the blocking read-backs among them (the CPU
    /// waited for their results): per sample, the round trips a hardware GPU pays beside its
    /// kernels.
    pub submissions: usize,
    pub read_backs: usize,
    /// Microseconds the CPU spent submitting, and blocked waiting for the GPU (the read-backs
    /// and the waits for a table build): beside the counts, where a hardware GPU's time goes.
    pub submit_micros: u64,
    pub waited_micros: u64,
    /// Steps whose proximity passes ran in the submission that selected and deformed
    /// ([`StepKernels::select_deform_and_clamp`]), and those whose passes so run moved vertices
    /// the pipeline did not take and were put back (the exact backstop undid a move, or the
    /// host's check of the move or the edges disagreed with the gate's).
    pub clamped_ahead: usize,
    pub dropped_ahead: usize,
    /// Steps whose proximity passes were skipped, their region one layer and a clear sheet
    /// where the moves end (`collide::clamp_on_a_clear_sheet`: the CPU's clamp would have
    /// searched nothing either), and steps recorded ahead without passes on that expectation
    /// whose region proved otherwise (their passes ran apart).
    pub skipped_passes: usize,
    pub passes_needed: usize,
    /// Steps whose passes ran ahead and the GPU's gate stopped before they moved anything
    /// (`sample_gate`; a run stops there): their selection outgrew its room, a ring its room, a
    /// vertex moved farther or an edge grew longer than the passes were sized for.
    pub gated_ahead: usize,
    /// Why the gate stopped them, per reason.
    pub gate_stops: GateStops,
    /// Submissions that ran several given samples of a stroke ([`StepKernels::given`]), and
    /// the samples taken from them.
    pub batches: usize,
    pub samples_ahead: usize,
    /// Steps of samples of several steps taken from such submissions.
    pub steps_ahead: usize,
    /// Samples whose move, over the step limit, the gate let go to their two steps recorded
    /// after their start in such a submission instead of stopping it there.
    pub split_ahead: usize,
}

impl Uploads {
    /// Counts a step the GPU's gate stopped, under each of its reasons (`stopped`:
    /// `GateStatus` bits; `longest`: its sample's longest move; `limit`: the step limit).
    pub fn count_gate_stop(&mut self, stopped: u32, longest: f32, limit: f32) {
        self.gated_ahead += 1;
        self.gate_stops.count(stopped, longest, limit);
    }
}

/// Why the GPU's gate stopped steps run ahead ([`Uploads::gated_ahead`]): a count per reason,
/// a stop counted under each of its reasons: where the GPU path's extra blocking read-backs
/// come from, whatever the adapter.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct GateStops {
    /// The selection outgrew the list's room.
    pub selection: usize,
    /// An exclusion ring outgrew its room.
    pub rings: usize,
    /// A vertex moved farther than the passes were sized for, still within one step.
    pub move_grew: usize,
    /// The sample moves farther than one step: it takes several, recorded after the stop.
    pub several_steps: usize,
    /// The samples before left an edge longer than the passes were sized for.
    pub edges: usize,
}

impl GateStops {
    /// Counts a stop the gate reported as `stopped` (`GateStatus` bits), its sample's longest
    /// move `longest` against the step `limit`.
    fn count(&mut self, stopped: u32, longest: f32, limit: f32) {
        let has = |bit: u32| usize::from(stopped & bit != 0);
        self.selection += has(GateStatus::SELECTION);
        self.rings += has(GateStatus::RINGS);
        self.edges += has(GateStatus::EDGES);
        if stopped & GateStatus::MOVE != 0 {
            // A NaN move is not within the limit either.
            if longest <= limit {
                self.move_grew += 1;
            } else {
                self.several_steps += 1;
            }
        }
    }

    /// The stops counted since `before`.
    pub fn since(self, before: GateStops) -> GateStops {
        GateStops {
            selection: self.selection - before.selection,
            rings: self.rings - before.rings,
            move_grew: self.move_grew - before.move_grew,
            several_steps: self.several_steps - before.several_steps,
            edges: self.edges - before.edges,
        }
    }
}

/// GPU memory held by kernels that keep the mesh there: as the wgpu backend's allocator reports
/// it (every live buffer, and the memory blocks they are carved from; `None` where the backend
/// keeps no report), and as our budget check (`SLAYER_GPU_BUDGET_MIB`) counts the mesh's copy.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct GpuMemory {
    pub allocated_bytes: Option<u64>,
    pub reserved_bytes: Option<u64>,
    /// `gpu::resident_bytes` of the mesh: what the budget check counts, and the budget.
    pub budget_bytes: u64,
    pub budget_limit_bytes: u64,
}

impl GpuMemory {
    /// Each figure the larger of the two: the peak over samples taken at different times.
    pub fn max(self, other: GpuMemory) -> GpuMemory {
        GpuMemory {
            allocated_bytes: self.allocated_bytes.max(other.allocated_bytes),
            reserved_bytes: self.reserved_bytes.max(other.reserved_bytes),
            budget_bytes: self.budget_bytes.max(other.budget_bytes),
            budget_limit_bytes: self.budget_limit_bytes.max(other.budget_limit_bytes),
        }
    }
}

/// What kernels that filter the backstop's first round (the GPU's) left the CPU to decide.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct BackstopFilter {
    /// Steps whose first round the kernels filtered: the CPU gathered no region for them
    /// unless an undo called for a second round.
    pub filtered: usize,
    /// Pairs over those steps the filter could not clear, decided on the CPU.
    pub undecided_pairs: usize,
    /// Steps whose pairs overflowed the filter's room: the CPU searched its region.
    pub overflowed: usize,
}

/// The CPU's selection (through the spatial hash, or by scanning) and deformation (rayon).
#[derive(Debug, Default, Clone, Copy)]
pub struct CpuKernels;

impl StepKernels for CpuKernels {
    fn name(&self) -> String {
        "cpu".into()
    }

    fn select(&mut self, state: &StrokeState<'_>, mesh: &Mesh, dab: &Dab) -> Vec<(u32, f32)> {
        select(state, mesh, dab)
    }

    fn deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        selection: &[(u32, f32)],
        _at: Option<CallAt>,
    ) -> Vec<Vec3> {
        deform(state, mesh, dab, selection)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gate_stop_is_counted_under_each_of_its_reasons() {
        let mut uploads = Uploads::default();
        let limit = 1.0;
        uploads.count_gate_stop(GateStatus::SELECTION | GateStatus::MOVE, 0.5, limit);
        uploads.count_gate_stop(GateStatus::MOVE, 2.5, limit);
        uploads.count_gate_stop(GateStatus::MOVE | GateStatus::EDGES, f32::NAN, limit);
        uploads.count_gate_stop(GateStatus::RINGS, 0.0, limit);
        assert_eq!(uploads.gated_ahead, 4);
        let expected = GateStops {
            selection: 1,
            rings: 1,
            move_grew: 1,
            several_steps: 2,
            edges: 1,
        };
        assert_eq!(uploads.gate_stops, expected);
        assert_eq!(expected.since(expected), GateStops::default());
    }
}
