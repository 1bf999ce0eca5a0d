// The gate of a run of samples recorded ahead in one submission (src/gpu/gate.rs): each sample
// checks, on the GPU, the assumptions its passes were recorded on — its selection within the
// list's room, every exclusion ring within its room, no vertex moving farther than the passes
// were sized for, no edge longer than they were sized for — and the first sample where one fails stops the run there: its moves are
// vacated before they are applied, and every later sample of the run selects nothing. The host
// reads each sample's status back and takes the samples before the stop.
// Codes as `src/abi/gate.rs` writes them (tests/wgsl.rs checks the values).

// Host struct: `GateParams`.
struct GateParams {
    // Slots of the selection list the sample's passes were sized for (the host's guess).
    capacity: u32,
    // `sample_gate`: one of the GATE_* stages.
    stage: u32,
    // The longest move the passes were sized for (non-negative).
    assumed_move: f32,
    // The bound on edge lengths at the sample's start the passes were sized for.
    max_edge: f32,
    // At a sample's start whose two steps are recorded after it: the step limit. A move over
    // it, by at most twice, defers to those steps instead of stopping the run. Zero: none.
    defer_over: f32,
    // Nonzero at one of those two steps: it runs only when its sample's start deferred.
    if_deferred: u32,
    _pad0: u32,
    _pad1: u32,
}

// Host struct: `GateStatus`. One per run, read back after every sample's decision.
struct GateStatus {
    // Zero while every sample so far held; else the STOPPED_* reasons of the sample that
    // stopped the run (STOPPED_EARLIER alone for the samples after it).
    stopped: u32,
    // The current sample's longest move as the bits of a non-negative f32, which order as the
    // floats do; a NaN or infinite move has larger bits than any finite one.
    longest: atomic<u32>,
    // The run's bound on edge lengths, as f32 bits: the host's at the run's start, grown by
    // `moved_edges` after every sample.
    edge: atomic<u32>,
    // 1 from the verdict of a start that deferred its move to its two steps until the next
    // ordinary call opens.
    deferred: u32,
}

// At the call's start, after `select`: the longest move reset (the deferral too, at an
// ordinary call), and the selection emptied in a stopped run or at a step whose sample did not
// defer, so that nothing after it in the call does any work.
const GATE_OPEN: u32 = 0u;
// After `deform`, `moving_entries` and `longest_move`: the sample's verdict.
const GATE_DECIDE: u32 = 1u;
// Per slot of the moving list: vacated when the run has stopped, at a start that deferred and
// at a step whose sample did not, so no pass moves anything.
const GATE_VACATE: u32 = 2u;

const STOPPED_EARLIER: u32 = 1u;
const STOPPED_SELECTION: u32 = 2u;
const STOPPED_RINGS: u32 = 4u;
const STOPPED_MOVE: u32 = 8u;
const STOPPED_EDGES: u32 = 16u;
