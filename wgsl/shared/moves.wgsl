// A step's moving vertices, as the collision kernels (`proximity`, `apply_moves`) share them.

// One entry of the step's selection. An entry whose vertex is INVALID (shared/mesh) is a vacant
// slot — a list slot past the selection's count, which `moving_entries` fills when the host
// sized the passes before it knew the count — and every kernel skips it.
struct MovingVertex {
    // Position at the start of the step.
    start: vec3<f32>,
    vertex: u32,
    layer: u32,
    // The vertex's exclusion ring (itself included) is words ring_start..ring_end of the rings array.
    ring_start: u32,
    ring_end: u32,
    _pad: u32,
}
