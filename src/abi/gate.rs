//! The gate of a run of samples recorded ahead (`wgsl/shared/gate.wgsl`: `longest_move`,
//! `sample_gate`, `moved_edges`): its parameters, stages and the status the host reads back.

use bytemuck::{Pod, Zeroable};

/// `GateParams` in `wgsl/shared/gate.wgsl` (`longest_move`, `sample_gate`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GateParams {
    /// Slots of the selection list the sample's passes were sized for.
    pub capacity: u32,
    /// One of [`GateStage`]'s codes (`sample_gate`).
    pub stage: u32,
    /// The longest move the passes were sized for (non-negative).
    pub assumed_move: f32,
    /// The bound on edge lengths at the sample's start the passes were sized for.
    pub max_edge: f32,
    /// A sample's start whose move is longer than this, and at most twice it, defers its move
    /// to its two steps recorded after it instead of stopping the run; zero: no such steps.
    pub defer_over: f32,
    /// Nonzero: a step of a sample that may defer, which runs only when that sample deferred.
    pub if_deferred: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

impl GateParams {
    /// A stage over `capacity` slots, for passes sized for moves and edges of at most
    /// `(assumed_move, max_edge)`.
    pub fn new(capacity: usize, stage: GateStage, (assumed_move, max_edge): (f32, f32)) -> Self {
        GateParams {
            capacity: capacity as u32,
            stage: stage as u32,
            assumed_move,
            max_edge,
            defer_over: 0.0,
            if_deferred: 0,
            _pad0: 0,
            _pad1: 0,
        }
    }

    /// The stage for a call that stands as `split` says to a sample that may defer its move.
    pub fn split(self, split: GateSplit) -> Self {
        GateParams {
            defer_over: split.defer_over,
            if_deferred: u32::from(split.if_deferred),
            ..self
        }
    }
}

/// How a call recorded in a run stands to a sample that may take two steps: a sample's
/// move that is over the step limit, by at most twice, need not stop the run when its two
/// steps are recorded after its start. Its start then moves nothing, and its steps run.
/// The default: an ordinary call, which runs unless the run stopped.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GateSplit {
    /// At a sample's start: the step limit, over which (by at most twice) its move defers to
    /// its two steps; zero where none were recorded.
    pub defer_over: f32,
    /// One of those two steps: it runs only when the start deferred.
    pub if_deferred: bool,
}

/// The `GATE_*` stages of `wgsl/sample_gate.wgsl`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum GateStage {
    /// After `select`: the longest move reset (and, at an ordinary call, the deferral); the
    /// selection emptied in a stopped run, and at a step whose sample did not defer.
    Open = 0,
    /// After `longest_move` (and the samples before's `moved_edges`): the sample's verdict.
    Decide = 1,
    /// Per slot of the moving list: vacated when the run has stopped, at a start that
    /// deferred, and at a step whose sample did not.
    Vacate = 2,
}

/// `GateStatus` in `wgsl/shared/gate.wgsl`: where a run recorded ahead stands, read back after
/// each sample's verdict.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Pod, Zeroable)]
pub struct GateStatus {
    /// Zero while every sample so far held; else the `STOPPED_*` reasons of the sample that
    /// stopped the run ([`GateStatus::EARLIER`] alone for the samples after it).
    pub stopped: u32,
    /// The sample's longest move, as the bits of a non-negative `f32`.
    pub longest: u32,
    /// The run's bound on edge lengths, as `f32` bits: the host's at the run's start, grown by
    /// `moved_edges` after every sample.
    pub edge: u32,
    /// 1 from the verdict of a sample's start that deferred its move to its two steps until
    /// the next ordinary call opens; else 0.
    pub deferred: u32,
}

impl GateStatus {
    /// An earlier sample of the run stopped it.
    pub const EARLIER: u32 = 1;
    /// The selection outgrew the list's room.
    pub const SELECTION: u32 = 2;
    /// An exclusion ring outgrew its room.
    pub const RINGS: u32 = 4;
    /// A vertex moved farther than the passes were sized for (or by NaN).
    pub const MOVE: u32 = 8;
    /// The samples before left an edge longer than the passes were sized for.
    pub const EDGES: u32 = 16;

    /// A run's status at its start, with the host's bound on edge lengths.
    pub fn starting(max_edge: f32) -> Self {
        GateStatus {
            edge: max_edge.to_bits(),
            ..GateStatus::default()
        }
    }

    /// The sample's longest move.
    pub fn longest_move(&self) -> f32 {
        f32::from_bits(self.longest)
    }

    /// The run's bound on edge lengths.
    pub fn edge_bound(&self) -> f32 {
        f32::from_bits(self.edge)
    }
}
