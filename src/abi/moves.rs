//! A step's moves and their collision handling: the moving list every such kernel reads
//! (`wgsl/shared/moves.wgsl`), the parameters of `moving_entries`, `proximity`, `apply_moves`,
//! `backstop`, `vertex_normals` and `moved_normals`, the packed topology's face words, and the
//! constants the proximity and backstop kernels share with their mirrors and the CPU pipeline.

use bytemuck::{Pod, Zeroable};

/// Words per face in the packed topology (`crate::gpu::PackedTopology`): face `f` is words
/// `4f..4f + 4` = (a, b, c, layer).
pub const FACE_WORDS: usize = 4;

/// A vertex already within the collision distance of a face is pulled back when its move
/// takes it closer by more than this share of the distance. A move along the face (a grab
/// carrying a patch over another layer) keeps the distance in exact arithmetic, and in floats
/// changes it by rounding only; without the slack, whether such a vertex is stopped would
/// depend on the last bits of the arithmetic, which differ between the CPU and a GPU (fused
/// multiply-adds), and the stop moves it by a whole step. The slack is also what a vertex
/// pressed against a surface may lose each step, and it adds up: at 1/1024 the plaster's 40
/// torture strokes (460 samples) ended with layers 0.45·d apart. 2⁻¹⁶·d is still ~50× the
/// rounding of a distance near `L` in f32. `wgsl/proximity.wgsl` has the same, and
/// `collide::pull_back` (the CPU backend) uses it too.
pub const CLAMP_SLACK: f32 = 1.0 / 65536.0;

/// Bisection fractions of `wgsl/proximity.wgsl` are multiples of 1 / PULL_SCALE; pull-back
/// amounts count in these steps.
pub const PULL_SCALE: f32 = 65536.0;

/// Share of a pair's size below which a separation is not trusted (`MARGIN` of
/// `wgsl/backstop_filter.wgsl`).
pub const BACKSTOP_MARGIN: f32 = 1.0 / 4096.0;

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
/// `crate::gpu::verdicts` turns them into these).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct PulledVertex {
    pub position: [f32; 3],
    /// 1 when pulled back.
    pub pulled: u32,
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

/// `BackstopParams` in `wgsl/backstop_filter.wgsl`.
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

/// `NormalParams` in `wgsl/vertex_normals.wgsl` and `wgsl/moved_normals.wgsl` (and
/// `wgsl/moved_edges.wgsl`).
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
