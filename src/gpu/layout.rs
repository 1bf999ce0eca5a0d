//! Host copies of the structs the kernels read. `tests/wgsl.rs` checks each size and field
//! offset against naga's layout of the WGSL declaration, so the two cannot drift apart.

use bytemuck::{Pod, Zeroable};

/// `CellKeyParams` in `wgsl/cell_keys.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct CellKeyParams {
    pub count: u32,
    /// Table size minus one; the table size is a power of two.
    pub table_mask: u32,
    pub inv_cell_size: f32,
    pub _pad: u32,
}

/// `CountParams` in `wgsl/shared/mesh.wgsl`: the element count of a one-dimensional pass.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct CountParams {
    pub count: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

impl CountParams {
    pub fn new(count: usize) -> Self {
        CountParams {
            count: count as u32,
            _pad0: 0,
            _pad1: 0,
            _pad2: 0,
        }
    }
}

/// `SelectParams` in `wgsl/select.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct SelectParams {
    pub center: [f32; 3],
    pub radius: f32,
    /// Lowest cell of the brush's box.
    pub cell_min: [i32; 3],
    pub table_mask: u32,
    /// Size of the box in cells.
    pub cell_span: [u32; 3],
    pub inv_cell_size: f32,
    /// Cells in the box, or vertices when `scan_vertices` is set.
    pub candidate_count: u32,
    pub scan_vertices: u32,
    /// A `FALLOFF_*` code of `wgsl/shared/brush.wgsl`.
    pub falloff: u32,
    pub blend_n: u32,
    pub capacity: u32,
    pub layer_count: u32,
    /// How far any vertex may have moved since the table was built.
    pub drift: f32,
    /// Nonzero: leave out vertices marked as filed in the overlay table.
    pub skip_marked: u32,
}

/// `SelectedVertex` in `wgsl/select.wgsl`: one entry of the compacted selection.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct SelectedVertex {
    pub vertex: u32,
    pub weight: f32,
}

/// `DeformParams` in `wgsl/deform.wgsl`: one dab.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct DeformParams {
    pub center: [f32; 3],
    pub radius: f32,
    pub normal: [f32; 3],
    pub strength: f32,
    pub plane_point: [f32; 3],
    pub pressure: f32,
    pub motion: [f32; 3],
    pub share: f32,
    /// A `BRUSH_*` code of `wgsl/shared/brush.wgsl`.
    pub kind: u32,
    pub sign: f32,
    pub capacity: u32,
    /// `FRAME_*` flags (`crate::cpu::FRAME_NORMAL_FROM_SUMS`, `FRAME_PLANE_FROM_SUMS`): which
    /// of normal and plane point the kernel takes from `brush_frame`'s sums.
    pub frame: u32,
}

/// `FrameParams` in `wgsl/brush_frame.wgsl`: where the brush is, and how much of the
/// selection list to sum.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct FrameParams {
    pub center: [f32; 3],
    pub inv_radius: f32,
    pub capacity: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// `DispatchParams` in `wgsl/dispatch_args.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct DispatchParams {
    pub workgroup_size: u32,
    pub max_per_dimension: u32,
    pub capacity: u32,
    pub per_item: u32,
}

/// `ProximityParams` in `wgsl/proximity.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct ProximityParams {
    /// Collision distance.
    pub distance: f32,
    /// Half-size of the box of cells searched around the tentative position.
    pub cell_reach: f32,
    /// Bucket entries farther than this from the tentative position (on some axis) are skipped.
    pub vertex_reach: f32,
    pub inv_cell_size: f32,
    pub table_mask: u32,
    /// Entries in the moving list.
    pub count: u32,
    /// Where the per-vertex (start, length) entries of the vertex→faces rows begin in the
    /// packed topology.
    pub vertex_rows_base: u32,
    /// 1 to test every face, 0 to test only faces with a marked vertex.
    pub all_faces: u32,
    /// Cells searched per entry (x, y, z), from the cell of x − `cell_reach`.
    pub span: [u32; 3],
    pub cells_per_entry: u32,
    /// Nonzero: walk the overlay table too (`overlay_mask + 1` buckets), leaving its members
    /// out of the main table's buckets.
    pub overlay: u32,
    pub overlay_mask: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// `BackstopParams` in `wgsl/backstop.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct BackstopParams {
    /// Half-size of the box of cells searched around each moved vertex.
    pub cell_reach: f32,
    /// Bucket entries farther than this from the moved vertex (on some axis) are skipped: two
    /// longest edges.
    pub vertex_reach: f32,
    pub inv_cell_size: f32,
    pub table_mask: u32,
    /// Entries in the moving list.
    pub count: u32,
    /// Where the per-vertex (start, length) entries of the vertex→faces rows begin in the
    /// packed topology.
    pub vertex_rows_base: u32,
    pub cells_per_entry: u32,
    /// Room for pairs in the output.
    pub capacity: u32,
    /// Cells searched per entry (x, y, z), from the cell of x − `cell_reach`.
    pub span: [u32; 3],
    /// Nonzero: walk the overlay table too, as `ProximityParams::overlay`.
    pub overlay: u32,
    pub overlay_mask: u32,
    /// Cells farther than this from the faces an entry tests are skipped: one longest edge and
    /// the filing drift.
    pub face_reach: f32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// `EntryParams` in `wgsl/moving_entries.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct EntryParams {
    /// Slots of the selection list covered (past its count they become vacant entries).
    pub capacity: u32,
    /// Graph distance of the exclusion ring.
    pub ring: u32,
    /// Words per entry in the rings buffer.
    pub ring_stride: u32,
    /// Where the vertex→faces rows start in the packed topology.
    pub vertex_rows_base: u32,
}

/// `ApplyParams` in `wgsl/apply_moves.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct ApplyParams {
    /// Entries in the moving list.
    pub count: u32,
    /// One of [`ApplyMode`]'s codes.
    pub mode: u32,
    /// What a pull stores as the next proximity pass's invocation count.
    pub next_invocations: u32,
    pub _pad: u32,
}

/// The `MODE_*` codes of `wgsl/apply_moves.wgsl`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum ApplyMode {
    /// Every entry to its brush target.
    Place = 0,
    /// Pulled entries to where the pass pulled them, marked.
    Pull = 1,
    /// Pulled entries back to their start (the last pass).
    PullLast = 2,
    /// Final positions out, marks cleared.
    Gather = 3,
    /// Marks set to the entry + 1 where the step moved the vertex, zero elsewhere: what the
    /// backstop filter reads (after `Gather`).
    MarkMoved = 4,
    /// Marks cleared (after the backstop filter).
    Clear = 5,
}

impl ApplyParams {
    pub fn new(count: usize, mode: ApplyMode) -> Self {
        ApplyParams {
            count: count as u32,
            mode: mode as u32,
            next_invocations: count as u32,
            _pad: 0,
        }
    }
}

/// `MovingVertex` in `wgsl/shared/moves.wgsl`: one entry of a step's selection.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct MovingVertex {
    /// Position at the start of the step.
    pub start: [f32; 3],
    pub vertex: u32,
    pub layer: u32,
    /// The exclusion ring is `rings[ring_start..ring_end]`.
    pub ring_start: u32,
    pub ring_end: u32,
    pub _pad: u32,
}

/// One entry's verdict after a proximity pass, on the host (the kernel keeps pull-back amounts;
/// [`crate::gpu::verdicts`] turns them into these).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct PulledVertex {
    pub position: [f32; 3],
    /// 1 when pulled back.
    pub pulled: u32,
}

/// `NormalParams` in `wgsl/vertex_normals.wgsl` and `wgsl/moved_normals.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct NormalParams {
    /// Vertices listed (`vertex_normals`), or slots of the moving list (`moved_normals`).
    pub count: u32,
    /// Where the per-vertex (start, length) entries of the vertex→faces rows begin in the
    /// packed topology.
    pub vertex_rows_base: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// `OverlayParams` in `wgsl/shared/overlay.wgsl` (`overlay_members`, `overlay_keys`,
/// `overlay_entries`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct OverlayParams {
    /// Invocations: slots of the moving list (`overlay_members`), of the member list (the
    /// others).
    pub count: u32,
    /// Slots the member list has room for.
    pub room: u32,
    /// Overlay table size minus one.
    pub table_mask: u32,
    pub inv_cell_size: f32,
}

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
