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
        }
    }
}

/// The `GATE_*` stages of `wgsl/sample_gate.wgsl`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum GateStage {
    /// After `select`: the longest move reset; a stopped run's selection emptied.
    Open = 0,
    /// After `longest_move` (and the samples before's `moved_edges`): the sample's verdict.
    Decide = 1,
    /// Per slot of the moving list: vacated when the run has stopped.
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
    pub _pad: u32,
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
