//! The buffers one step records into (selection list, targets, moving list and rings, the
//! proximity passes' pulls and finals, the backstop filter's pairs, the brush frame's sums, the
//! run gate's status), reused from step to step and grown when a step needs more, never
//! reallocated otherwise; and how what a clamp left in them is read back ([`ClampRead`]).

use glam::Vec3;

use super::resident::Resident;
use crate::collide::Backstop;
use crate::gpu::reusable::ReusableBuffer;
use crate::gpu::{
    GateBuffers, GateStatus, GpuContext, GpuError, MovingVertex, PAIRS_GUESS, frame_sums_buffer,
    indirect_args_buffer, ring_bytes,
};
use crate::mesh::Mesh;

/// Per-step buffers, reused from step to step.
pub(super) struct StepBuffers {
    pub(super) selected: ReusableBuffer,
    pub(super) selection_count: wgpu::Buffer,
    pub(super) targets: ReusableBuffer,
    pub(super) moving: ReusableBuffer,
    /// Exclusion rings built by the host, one after another.
    pub(super) rings: ReusableBuffer,
    /// Exclusion rings built by `moving_entries`, `RING_STRIDE` words a slot, and how many
    /// did not fit.
    pub(super) ring_slots: ReusableBuffer,
    pub(super) ring_overflows: wgpu::Buffer,
    /// Per entry: the last proximity pass's pull-back amount.
    pub(super) pulls: ReusableBuffer,
    pub(super) finals: ReusableBuffer,
    /// The backstop filter's undecided pairs, their count, and the room there is for them.
    pub(super) pairs: ReusableBuffer,
    pub(super) pair_count: wgpu::Buffer,
    pub(super) pair_capacity: usize,
    pub(super) next_count: wgpu::Buffer,
    pub(super) pass_args: wgpu::Buffer,
    pub(super) apply_args: wgpu::Buffer,
    /// The brush frame's sums, and its dispatch sized from the selection count.
    pub(super) frame_sums: wgpu::Buffer,
    pub(super) frame_args: wgpu::Buffer,
    /// A run's [`GateStatus`]: whether a sample has stopped it, the current sample's longest
    /// move (`longest_move`) and the run's edge bound (`moved_edges`).
    pub(super) gate_status: wgpu::Buffer,
    /// The moving lists of a run's steps of one sample, one after another, for the normals
    /// after its last step.
    pub(super) held_moving: ReusableBuffer,
}

impl StepBuffers {
    /// What the run's gate reads and writes for a step recorded into these buffers.
    pub(super) fn gate<'b>(&'b self, r: &'b Resident) -> GateBuffers<'b> {
        GateBuffers {
            positions: &r.vertices.positions,
            selected: &r.selection.selected,
            selection_count: &r.selection.count,
            targets: self.targets.buffer(),
            ring_overflows: &self.ring_overflows,
            moving: self.moving.buffer(),
            status: &self.gate_status,
        }
    }

    pub(super) fn new(gpu: &GpuContext) -> StepBuffers {
        StepBuffers {
            selected: ReusableBuffer::storage("selected"),
            selection_count: gpu.output_buffer::<u32>("selection count", 1),
            targets: ReusableBuffer::storage("targets"),
            moving: ReusableBuffer::storage("moving"),
            rings: ReusableBuffer::paged("exclusion rings"),
            ring_slots: ReusableBuffer::storage("exclusion ring slots"),
            ring_overflows: gpu.output_buffer::<u32>("ring overflows", 1),
            pulls: ReusableBuffer::storage("pull-back amounts"),
            finals: ReusableBuffer::storage("finals"),
            pairs: ReusableBuffer::storage("undecided pairs"),
            pair_count: gpu.output_buffer::<u32>("undecided pair count", 1),
            pair_capacity: PAIRS_GUESS,
            next_count: gpu.output_buffer::<u32>("next pass count", 1),
            pass_args: indirect_args_buffer(gpu, "proximity pass sizes"),
            apply_args: indirect_args_buffer(gpu, "apply pass sizes"),
            frame_sums: frame_sums_buffer(gpu),
            frame_args: indirect_args_buffer(gpu, "brush frame sizes"),
            gate_status: gpu.output_buffer::<GateStatus>("run gate status", 1),
            held_moving: ReusableBuffer::storage("moving lists of a sample's steps"),
        }
    }

    /// Starts the gate for a single step's passes or a run's: no stop yet, and the edge bound
    /// at `max_edge` (the pipeline's). Written before the submission's commands run.
    pub(super) fn start_gate(&self, gpu: &GpuContext, max_edge: f32) {
        gpu.queue.write_buffer(
            &self.gate_status,
            0,
            bytemuck::bytes_of(&GateStatus::starting(max_edge)),
        );
    }

    /// Room for [`record_sample`](super::select_deform::record_sample) over `guess` slots (with
    /// `ahead`, its passes too: the topology made resident).
    pub(super) fn reserve_sample(
        &mut self,
        gpu: &GpuContext,
        (r, mesh): (&mut Resident, &Mesh),
        guess: usize,
        deforms: bool,
        ahead: bool,
        filter: bool,
    ) -> Result<(), GpuError> {
        if deforms {
            self.targets
                .reserve(gpu, (guess * std::mem::size_of::<Vec3>()) as u64)?;
        }
        if ahead {
            r.ensure_topology(gpu, mesh)?;
            self.moving
                .reserve(gpu, (guess * std::mem::size_of::<MovingVertex>()) as u64)?;
            self.ring_slots.reserve(gpu, ring_bytes(guess))?;
            self.reserve_clamp(gpu, guess, filter)?;
        }
        Ok(())
    }

    /// Room for a clamp over `count` slots (`record_clamp`), before its buffers are borrowed.
    pub(super) fn reserve_clamp(
        &mut self,
        gpu: &GpuContext,
        count: usize,
        filter: bool,
    ) -> Result<(), GpuError> {
        self.pulls
            .reserve(gpu, (count * std::mem::size_of::<u32>()) as u64)?;
        self.finals
            .reserve(gpu, (count * std::mem::size_of::<Vec3>()) as u64)?;
        if filter {
            let pair_bytes = (self.pair_capacity * std::mem::size_of::<[u32; 2]>()) as u64;
            self.pairs.reserve(gpu, pair_bytes)?;
        }
        Ok(())
    }

    /// The finals of a clamp over `count` slots and what it leaves the backstop, from the
    /// bytes read back (finals first, then the filter's count and pairs). An overflow of the
    /// pairs' room grows it for the next step.
    pub(super) fn parse_clamp(
        &mut self,
        data: &[u8],
        count: usize,
        read: ClampRead,
    ) -> (Vec<Vec3>, Backstop) {
        let at = read.finals_bytes as usize;
        let finals = bytemuck::pod_collect_to_vec(&data[..count * std::mem::size_of::<Vec3>()]);
        let Some(pair_bytes) = read.pair_bytes else {
            return (finals, Backstop::Gather);
        };
        let found =
            u32::from_le_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]]) as usize;
        // The room the recording had (a later recording may have more).
        let room = pair_bytes as usize / std::mem::size_of::<[u32; 2]>();
        if found > room {
            // Room for them next time; this step's backstop searches on the CPU.
            self.pair_capacity = self.pair_capacity.max(found.next_power_of_two());
            return (finals, Backstop::Gather);
        }
        let pairs = bytemuck::pod_collect_to_vec(&data[at + 4..at + 4 + 8 * found]);
        (finals, Backstop::Undecided(pairs))
    }
}

/// What a recorded clamp leaves to read back after it: the finals, and with the filter its
/// pair count and pairs.
#[derive(Debug, Clone, Copy)]
pub(super) struct ClampRead {
    pub(super) finals_bytes: u64,
    pub(super) pair_bytes: Option<u64>,
    /// The finals are the targets: no passes ran
    /// ([`PassBounds::skip_passes`](super::clamp::PassBounds)).
    pub(super) without_passes: bool,
}
