// Per-vertex bits and sentinels, as in `src/mesh/attributes.rs::VertexFlags` and
// `src/mesh::INVALID` (tests/wgsl.rs checks the values against the host's).

const VERTEX_LOCKED: u32 = 1u;
const VERTEX_MASKED: u32 = 2u;
// One step of a partial mask (flags bits 8..15).
const MASK_STEP: f32 = 1.0 / 255.0;
const VERTEX_DEAD: u32 = 4u;

const INVALID: u32 = 0xffffffffu;

// Element count of a one-dimensional pass; padded to 16 bytes for the uniform address space.
struct CountParams {
    count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

