//! A step's selection, brush frame and deformation on the GPU, in one submission with one
//! read-back where it can be ([`GpuKernels::gpu_select_and_deform`]): the selection's count, a
//! guessed head of the list and its targets together; at a sample's start also the brush
//! frame, summed by `brush_frame` and read by `deform` on the GPU; with a step limit, the
//! step's proximity passes too (`super::clamp`). [`record_sample`] records one such step, for
//! this submission or for one of a run ahead (`super::run_ahead`).

use glam::Vec3;

use super::GpuKernels;
use super::clamp::{ClampedAhead, PassBounds, put_back, record_clamp};
use super::hashed::{TableUse, cell_size};
use super::resident::Resident;
use super::step_buffers::{ClampRead, StepBuffers};
use crate::abi::{DeformParams, frame_params};
use crate::brush::{Dab, DabFrame};
use crate::collide::StrokeState;
use crate::cpu::FRAME_SUM_WORDS;
use crate::gpu::{
    BrushSphere, BuiltEntryBuffers, DeformBuffers, EntryBuffers, FRAME_WORKGROUP_SIZE, GateSplit,
    GateStatus, GpuContext, GpuError, HashedVertices, SELECTION_GUESS, SelectedVertex,
    SelectionBuffers, SelectionRead, Workgroups, deform_params, entry_params, record_brush_frame,
    record_deform, record_dispatch_args, record_gate_check, record_gate_open,
    record_moving_entries, record_select, ring_bytes,
};
use crate::mesh::Mesh;
use crate::pipeline::step::{frame_flags, frame_of_sums, longest_move};
use crate::pipeline::{Deformed, FrameSource};

impl GpuKernels {
    /// Deforms `selection` (the pipeline's) under `dab` on the GPU: the list uploaded, the
    /// targets read back. Ahead of the passes that would have moved it, whatever ran ahead is
    /// dropped.
    pub(super) fn gpu_deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        selection: &[(u32, f32)],
    ) -> Result<Vec<Vec3>, GpuError> {
        if selection.is_empty() {
            return Ok(Vec::new());
        }
        self.check_injected_failure()?;
        self.drop_all_ahead(mesh);
        let (gpu, step, readback) = (&self.gpu, &mut self.step, &mut self.readback);
        let r = GpuKernels::prepare(
            gpu,
            (&mut self.resident, &mut self.uploads),
            mesh,
            cell_size(state),
            TableUse::None,
        )?;
        let entries: Vec<SelectedVertex> = selection
            .iter()
            .map(|&(vertex, weight)| SelectedVertex { vertex, weight })
            .collect();
        step.selected.upload(gpu, &entries)?;
        gpu.queue.write_buffer(
            &step.selection_count,
            0,
            bytemuck::bytes_of(&(entries.len() as u32)),
        );
        let bytes = (entries.len() * std::mem::size_of::<Vec3>()) as u64;
        step.targets.reserve(gpu, bytes)?;
        let mut encoder = gpu.encoder("deform");
        record_deform(
            gpu,
            &mut encoder,
            &DeformBuffers {
                selection: SelectionBuffers {
                    positions: &r.vertices.positions,
                    normals: &r.normals,
                    selected: step.selected.buffer(),
                    selection_count: &step.selection_count,
                },
                neighbour_rows: &r.neighbour_table,
                neighbours: &r.neighbours,
                frame_sums: &step.frame_sums,
            },
            &deform_params(dab, entries.len()),
            step.targets.buffer(),
        )?;
        let data = readback.read_back_parts(gpu, encoder, &[(step.targets.buffer(), bytes)])?;
        Ok(bytemuck::pod_collect_to_vec(&data))
    }

    /// Selection, brush frame and deformation in one submission: the selection kernel fills
    /// the resident list; at a sample's start `brush_frame` sums it (dispatched from the
    /// count) and `deform` takes the frame from the sums; `deform` moves the first `guess`
    /// entries. The count, that head of the list, the sums and the targets come back in one
    /// map (`GpuSelection::submit_and_read`). A selection longer than the guess reads the rest
    /// of the list and deforms it apart.
    ///
    /// With `clamp_within` (a step limit), the same submission goes on through the step's proximity
    /// passes and filter: `moving_entries` builds the moving list and the rings from the selection
    /// list, and the passes run over the guessed slots, sized as if no vertex moved farther than
    /// [`AHEAD_MOVE_GROWTH`](super::clamp::AHEAD_MOVE_GROWTH) times the last step's longest move,
    /// within the limit. The result is kept for the pipeline's `clamp` ([`ClampedAhead`]) when that
    /// held (so the step is one step) and the selection and rings fitted their room; otherwise the
    /// positions the passes wrote are put back.
    pub(super) fn gpu_select_and_deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        (source, deforms): (FrameSource, bool),
        clamp_within: Option<f32>,
    ) -> Result<Deformed, GpuError> {
        self.check_injected_failure()?;
        self.check_gpu_filing(mesh);
        self.drop_all_ahead(mesh);
        // The passes' reach, and their work with its cube, grows with the move they assume:
        // twice the last step's longest move (within the limit), which consecutive steps of a
        // stroke rarely exceed.
        let assumed_move = clamp_within
            .filter(|_| deforms && self.proximity_on_gpu && self.clamp_ahead)
            .map(|limit| self.assumed_move(limit));
        let SubmittedSample {
            read,
            layout,
            guess,
            assumed_move,
        } = self.submit_sample(state, mesh, dab, (source, deforms), assumed_move)?;
        let list = read.list;
        let count = list.len();
        let whole_list = read.head == count;
        let parts = layout.split(&read.extra, dab);
        self.last_selection = count;
        let (order, selection) = in_vertex_order(&list);
        let targets: Option<Vec<Vec3>> = (deforms && count > 0 && whole_list).then(|| {
            permuted(
                &order,
                &bytemuck::pod_collect_to_vec(&parts.targets[..count * 12]),
            )
        });
        let frame = parts.frame;
        let longest = targets
            .as_ref()
            .map(|targets| longest_move(mesh, &selection, targets));
        if let Some(longest) = longest {
            self.last_move = longest;
        }
        if let (Some(assumed), Some(clamp_read), Some(limit)) =
            (assumed_move, layout.clamp, clamp_within)
        {
            let moved = (targets.as_ref(), longest);
            let read = (guess, assumed, clamp_read);
            self.keep_ahead(mesh, (&selection, &order), moved, &parts, read, limit);
        }
        let targets = match (deforms && count > 0, targets) {
            (true, None) => {
                let dab = Dab { frame, ..*dab };
                Some(self.gpu_deform(state, mesh, &dab, &selection)?)
            }
            (_, targets) => targets,
        };
        Ok(Deformed {
            selection,
            frame,
            targets,
            deform_millis: 0.0,
        })
    }

    /// [`GpuKernels::gpu_select_and_deform`]'s submission: the step recorded
    /// ([`record_sample`]) over a guessed head of the selection list — with its passes when an
    /// `assumed_move` is given and the rings of the guessed slots fit one binding — submitted
    /// and read back.
    fn submit_sample(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        (source, deforms): (FrameSource, bool),
        assumed_move: Option<f32>,
    ) -> Result<SubmittedSample, GpuError> {
        let filter = self.backstop_on_gpu;
        let skip_passes = self.skips_passes(state, mesh);
        let (gpu, step, readback) = (&self.gpu, &mut self.step, &mut self.readback);
        let r = GpuKernels::prepare(
            gpu,
            (&mut self.resident, &mut self.uploads),
            mesh,
            cell_size(state),
            match assumed_move {
                Some(_) => TableUse::Proximity,
                None => TableUse::Select {
                    radius: dab.brush.radius,
                },
            },
        )?;
        let capacity = r.selection.capacity;
        let guess = selection_guess(self.last_selection, capacity);
        // The rings of the guessed slots must fit one binding (`moving_entries` writes them).
        let assumed_move = assumed_move
            .filter(|_| ring_bytes(guess) <= gpu.limits.max_storage_buffer_binding_size);
        step.reserve_sample(
            gpu,
            (r, mesh),
            guess,
            deforms,
            assumed_move.is_some(),
            filter,
        )?;
        let r = &*r;
        let mut encoder = gpu.encoder("select and deform");
        let ahead = assumed_move.map(|assumed_move| AheadBounds {
            assumed_move,
            drift: r.hashed().drift,
            split: GateSplit::default(),
            skip_passes,
        });
        if ahead.is_some() {
            step.start_gate(gpu, state.max_edge);
        }
        let recorded = record_sample(
            gpu,
            &mut encoder,
            (r, step),
            state,
            dab,
            (source.into(), deforms),
            guess,
            ahead,
            filter,
        )?;
        let read = r
            .selection
            .submit_and_read(gpu, encoder, readback, guess, &recorded.parts)?;
        Ok(SubmittedSample {
            read,
            layout: recorded.layout,
            guess,
            assumed_move,
        })
    }

    /// After a submission that ran a step's passes ahead, sized for moves up to `assumed`:
    /// keeps them for the pipeline's `clamp` ([`ClampedAhead`]) when they hold — the whole
    /// list read, the moves within that, the rings within their room, the gate open —
    /// otherwise counts them stopped by the gate or puts back the rows they moved.
    fn keep_ahead(
        &mut self,
        mesh: &Mesh,
        (selection, order): (&[(u32, f32)], &[usize]),
        (targets, longest): (Option<&Vec<Vec3>>, Option<f32>),
        parts: &SampleBytes<'_>,
        (guess, assumed, clamp_read): (usize, f32, ClampRead),
        limit: f32,
    ) {
        let vertices: Vec<u32> = selection.iter().map(|&(v, _)| v).collect();
        // Within the assumed move, which is within the step limit: one step, which moves
        // the selection to exactly these targets. The gate checked the same on the GPU.
        let stop = parts.gate.filter(|g| g.stopped != 0);
        let kept = targets.filter(|_| {
            stop.is_none()
                && parts.ring_overflows == Some(0)
                && longest.is_some_and(|l| l <= assumed)
        });
        match kept {
            Some(targets) => {
                let (finals, backstop) = self.step.parse_clamp(parts.clamp, guess, clamp_read);
                self.ahead = Some(ClampedAhead {
                    vertices,
                    targets: targets.clone(),
                    finals: permuted(order, &finals),
                    backstop,
                    without_passes: clamp_read.without_passes,
                });
            }
            // Nothing selected: nothing moved, nothing to drop.
            None if vertices.is_empty() => {}
            None => match stop {
                // Stopped by the gate before they moved anything.
                Some(status) => {
                    let longest = longest.unwrap_or(status.longest_move());
                    self.uploads.count_gate_stop(status.stopped, longest, limit);
                }
                // The passes moved what they were wrong about.
                None => put_back(
                    &self.gpu,
                    self.resident.as_ref(),
                    &mut self.uploads,
                    mesh,
                    &vertices,
                ),
            },
        }
    }
}

/// What [`GpuKernels::submit_sample`] read back, how it splits, the guessed head of the list
/// it read with the count, and the move its passes assumed (`None`: no passes ran).
struct SubmittedSample {
    read: SelectionRead,
    layout: SampleLayout,
    guess: usize,
    assumed_move: Option<f32>,
}

/// The head of the selection list read back with its count: twice the `last` selection,
/// within the list's `capacity`.
pub(super) fn selection_guess(last: usize, capacity: usize) -> usize {
    (2 * last).max(SELECTION_GUESS).min(capacity)
}

/// How a sample's passes, recorded before its moves are known, are sized: for moves up to
/// `assumed_move`, over a table whose vertices may have drifted `drift` from where they were
/// filed. Such passes go through the gate (`sample_gate`, started by
/// [`StepBuffers::start_gate`]): where those assumptions fail they move nothing. `split`: how
/// the call stands to a sample of a run that may defer its move to two steps.
#[derive(Debug, Clone, Copy)]
pub(super) struct AheadBounds {
    pub(super) assumed_move: f32,
    pub(super) drift: f32,
    pub(super) split: GateSplit,
    /// Record no passes, on the expectation that the step's region is one layer and a clear
    /// sheet where its moves end (the targets placed and gathered as finals): the host checks
    /// it before it takes them ([`ClampedAhead::without_passes`]).
    pub(super) skip_passes: bool,
}

/// Where a recorded call's brush frame comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum CallFrame {
    /// Summed from the call's selection (a sample's start; `normal`: the sample's own).
    Summed { normal: Option<Vec3> },
    /// From the sums the sample's start left, recorded before it in the same submission (a
    /// step of a sample that may defer its move).
    SummedAtStart { normal: Option<Vec3> },
    /// The dab's, as given.
    Dab,
}

impl From<FrameSource> for CallFrame {
    fn from(source: FrameSource) -> Self {
        match source {
            FrameSource::Selection { normal } => CallFrame::Summed { normal },
            FrameSource::Dab => CallFrame::Dab,
        }
    }
}

/// What [`record_sample`] leaves to read back after the selection's count and list: `parts`,
/// in order, and how to split them.
pub(super) struct RecordedSample<'b> {
    pub(super) parts: Vec<(&'b wgpu::Buffer, u64)>,
    pub(super) layout: SampleLayout,
}

/// How a recorded sample's parts split.
#[derive(Debug, Clone, Copy)]
pub(super) struct SampleLayout {
    /// The sample's own normal when the frame is summed from the selection.
    pub(super) frame_from_selection: Option<Option<Vec3>>,
    pub(super) target_bytes: u64,
    /// Where the passes ran (through the gate, whose status follows the ring overflows).
    pub(super) clamp: Option<ClampRead>,
}

/// A recorded sample's bytes after the selection list, split.
pub(super) struct SampleBytes<'d> {
    pub(super) frame: DabFrame,
    /// `target_bytes` of targets, in the list's order (empty for a brush that does not move).
    pub(super) targets: &'d [u8],
    /// Rings `moving_entries` cut short, where the passes ran.
    pub(super) ring_overflows: Option<u32>,
    /// The gate's verdict, where the passes went through it: when it stopped them they moved
    /// nothing.
    pub(super) gate: Option<GateStatus>,
    /// The rest: what `StepBuffers::parse_clamp` reads.
    pub(super) clamp: &'d [u8],
}

impl SampleLayout {
    pub(super) fn split<'d>(&self, mut rest: &'d [u8], dab: &Dab) -> SampleBytes<'d> {
        let mut take = |bytes: u64| {
            let (part, after) = rest.split_at(bytes as usize);
            rest = after;
            part
        };
        let frame = match self.frame_from_selection {
            Some(normal) => {
                let sums = take((FRAME_SUM_WORDS * 4) as u64);
                frame_of_sums(&bytemuck::pod_read_unaligned(sums), dab, normal)
            }
            None => dab.frame,
        };
        let targets = take(self.target_bytes);
        let ring_overflows = self
            .clamp
            .map(|_| u32::from_le_bytes(take(4).try_into().expect("four bytes")));
        let gate = self
            .clamp
            .map(|_| bytemuck::pod_read_unaligned(take(std::mem::size_of::<GateStatus>() as u64)));
        SampleBytes {
            frame,
            targets,
            ring_overflows,
            gate,
            clamp: rest,
        }
    }
}

/// Records one sample's step into `encoder`: selection under `dab` (into the resident list),
/// the brush frame as `frame` says (at a sample's start summed from it), with `deforms` the
/// deformation of the first `guess` entries, and with `ahead` `moving_entries` and the step's
/// proximity passes and filter over those slots. `state.max_edge` bounds the edges at the
/// step's start. The buffers are reserved beforehand.
#[allow(clippy::too_many_arguments)]
pub(super) fn record_sample<'b>(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (r, step): (&'b Resident, &'b StepBuffers),
    state: &StrokeState<'_>,
    dab: &Dab,
    (frame, deforms): (CallFrame, bool),
    guess: usize,
    ahead: Option<AheadBounds>,
    filter: bool,
) -> Result<RecordedSample<'b>, GpuError> {
    let drift = ahead.map_or(r.hashed().drift, |a| a.drift);
    record_brush_selection(gpu, encoder, r, state.active, dab, drift)?;
    if let Some(ahead) = ahead {
        record_gate_open(gpu, encoder, &step.gate(r), ahead.split)?;
    }
    let inputs = SelectionBuffers {
        positions: &r.vertices.positions,
        normals: &r.normals,
        selected: &r.selection.selected,
        selection_count: &r.selection.count,
    };
    let mut params = deform_params(dab, guess);
    let mut parts = Vec::new();
    let frame_from_selection = match frame {
        CallFrame::Summed { normal } => {
            record_frame_sums(gpu, encoder, (r, step), &inputs, dab, normal, &mut params)?;
            parts.push((&step.frame_sums, (FRAME_SUM_WORDS * 4) as u64));
            Some(normal)
        }
        CallFrame::SummedAtStart { normal } => {
            frame_from_sums(&mut params, normal);
            None
        }
        CallFrame::Dab => None,
    };
    let target_bytes = if deforms {
        (guess * std::mem::size_of::<Vec3>()) as u64
    } else {
        0
    };
    if deforms {
        record_deform(
            gpu,
            encoder,
            &DeformBuffers {
                selection: inputs,
                neighbour_rows: &r.neighbour_table,
                neighbours: &r.neighbours,
                frame_sums: &step.frame_sums,
            },
            &params,
            step.targets.buffer(),
        )?;
        parts.push((step.targets.buffer(), target_bytes));
    }
    let mut clamp = None;
    if let Some(ahead) = ahead {
        let slots = (ahead, guess);
        let passes = record_ahead_passes(gpu, encoder, (r, step), state, slots, filter, &mut parts);
        clamp = Some(passes?);
    }
    Ok(RecordedSample {
        parts,
        layout: SampleLayout {
            frame_from_selection,
            target_bytes,
            clamp,
        },
    })
}

/// [`record_sample`]'s brush frame, summed from the selection (dispatched from its count)
/// into `step.frame_sums`, and `params` set to take the frame from those sums (`normal`: the
/// sample's own, if it brings one).
fn record_frame_sums(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (r, step): (&Resident, &StepBuffers),
    inputs: &SelectionBuffers<'_>,
    dab: &Dab,
    normal: Option<Vec3>,
    params: &mut DeformParams,
) -> Result<(), GpuError> {
    let capacity = r.selection.capacity;
    frame_from_sums(params, normal);
    record_dispatch_args(
        gpu,
        encoder,
        &r.selection.count,
        (capacity, 1),
        FRAME_WORKGROUP_SIZE,
        &step.frame_args,
    )?;
    record_brush_frame(
        gpu,
        encoder,
        inputs,
        &frame_params(dab.frame.center, dab.brush.radius, capacity),
        &step.frame_sums,
        Workgroups::Indirect(&step.frame_args),
    )
}

/// Sets `params` to take the brush frame from `brush_frame`'s sums (`normal`: the sample's
/// own, if it brings one).
fn frame_from_sums(params: &mut DeformParams, normal: Option<Vec3>) {
    params.frame = frame_flags(normal);
    params.normal = normal.unwrap_or(Vec3::Z).to_array();
}

/// [`record_sample`]'s passes, run ahead of the moves: `moving_entries` over the first `guess`
/// slots of the selection list, the gate's check of the sample, and the step's proximity
/// passes and filter over those slots ([`record_clamp`]), sized by `ahead`. What they leave
/// to read back is appended to `parts`.
fn record_ahead_passes<'b>(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (r, step): (&'b Resident, &'b StepBuffers),
    state: &StrokeState<'_>,
    (ahead, guess): (AheadBounds, usize),
    filter: bool,
    parts: &mut Vec<(&'b wgpu::Buffer, u64)>,
) -> Result<ClampRead, GpuError> {
    let AheadBounds {
        assumed_move,
        drift,
        split,
        ..
    } = ahead;
    let Some(topology) = &r.topology else {
        unreachable!("the caller made the topology resident");
    };
    encoder.clear_buffer(&step.ring_overflows, 0, None);
    record_moving_entries(
        gpu,
        encoder,
        &EntryBuffers {
            positions: &r.vertices.positions,
            layers: &r.vertices.layers,
            selected: &r.selection.selected,
            selection_count: &r.selection.count,
            topology: &topology.buffer,
        },
        &entry_params(guess, state.ring, topology.layout.vertex_rows_base),
        &BuiltEntryBuffers {
            moving: step.moving.buffer(),
            rings: step.ring_slots.buffer(),
            overflows: &step.ring_overflows,
        },
    )?;
    record_gate_check(
        gpu,
        encoder,
        &step.gate(r),
        (guess, assumed_move, state.max_edge),
        split,
    )?;
    // No vertex moves farther than assumed, so no edge grows by more than twice that.
    let bounds = PassBounds {
        count: guess,
        step_move: assumed_move,
        moved_edge: state.max_edge + 2.0 * assumed_move,
        drift,
        counted_by: Some(&r.selection.count),
        skip_passes: ahead.skip_passes,
    };
    let read = record_clamp(gpu, encoder, (r, step), state, &bounds, filter)?;
    parts.push((&step.ring_overflows, 4));
    parts.push((&step.gate_status, std::mem::size_of::<GateStatus>() as u64));
    parts.push((step.finals.buffer(), read.finals_bytes));
    if let Some(pair_bytes) = read.pair_bytes {
        parts.push((&step.pair_count, 4));
        parts.push((step.pairs.buffer(), pair_bytes));
    }
    Ok(read)
}

/// The order that sorts a selection list by vertex, and the list so sorted: the kernels append
/// in whatever order their threads ran; the pipeline works in vertex order (its sums and the
/// CPU's agree then).
pub(super) fn in_vertex_order(list: &[SelectedVertex]) -> (Vec<usize>, Vec<(u32, f32)>) {
    let mut order: Vec<usize> = (0..list.len()).collect();
    order.sort_unstable_by_key(|&i| list[i].vertex);
    let selection = order
        .iter()
        .map(|&i| (list[i].vertex, list[i].weight))
        .collect();
    (order, selection)
}

/// `values` (one per list entry) permuted as [`in_vertex_order`] sorted the list.
pub(super) fn permuted<T: Copy>(order: &[usize], values: &[T]) -> Vec<T> {
    order.iter().map(|&i| values[i]).collect()
}

/// Records a selection under `dab` into the resident selection buffers.
fn record_brush_selection(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    r: &Resident,
    active: &[bool],
    dab: &Dab,
    drift: f32,
) -> Result<(), GpuError> {
    let hashed = r.hashed();
    let active_words: Vec<u32> = active.iter().map(|&a| a as u32).collect();
    let active_buffer = gpu.storage_buffer("active layers", &active_words, false);
    record_select(
        gpu,
        encoder,
        &r.vertices,
        &active_buffer,
        active.len(),
        &HashedVertices {
            table: &hashed.table,
            positions: &hashed.positions,
            drift,
            overlay: hashed.overlay(),
        },
        &BrushSphere {
            center: dab.frame.center,
            radius: dab.brush.radius,
            falloff: dab.brush.falloff,
        },
        &r.selection,
    )
}
