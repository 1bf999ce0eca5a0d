// A step's moving vertices, as the collision kernels (`proximity`, `apply_moves`) share them.

// One entry of the step's selection.
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
