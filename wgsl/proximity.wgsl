// Vertex–triangle proximity and the collision response of one Jacobi pass (sLayer Algorithm 2
// "collide"; DESIGN §3): `pull_back` of src/pipeline/step.rs for every entry of the step's
// selection. An entry whose vertex sits at its start has nothing to test. Otherwise the vertex,
// at its tentative position x, is tested against every face near x outside its own
// neighbourhood, and where a face is closer than min(d, its distance from the start) the move
// is bisected for the last safe fraction; the result is the smallest fraction over all faces.
// Taking a minimum makes the result independent of the order faces are met in, and of meeting
// a face twice (through two of its vertices, or two cells sharing a bucket).
// CPU mirror: src/cpu/proximity.rs.

#import shared/grid
#import shared/geom

struct ProximityParams {
    // Collision distance d.
    distance: f32,
    // Cells searched: those of the box x ± cell_reach. It must cover the hashed position of
    // every vertex of a face within d of x: d + longest edge + how far any vertex has moved
    // since the table was built.
    cell_reach: f32,
    // A face within d of x has every vertex (at current positions) within d + longest edge of
    // x; bucket entries farther than this on some axis are skipped. This replaces the cell
    // check of other queries (positions may have left the cells they were filed under).
    vertex_reach: f32,
    inv_cell_size: f32,
    table_mask: u32,
    // Entries in `moving`.
    count: u32,
    // Where the vertex→faces rows start in `topology`.
    vertex_faces_base: u32,
    // 1: test every face (the first pass); 0: only faces with a vertex marked in `marks`.
    all_faces: u32,
}

// One entry of the step's selection.
struct MovingVertex {
    // Position at the start of the step.
    start: vec3<f32>,
    vertex: u32,
    layer: u32,
    // The vertex's exclusion ring (itself included) is rings[ring_start..ring_end].
    ring_start: u32,
    ring_end: u32,
    _pad: u32,
}

// The pass's verdict on one entry.
struct PulledVertex {
    // Where the vertex must be: pulled back along its move, or x unchanged.
    position: vec3<f32>,
    // 1 when pulled back.
    pulled: u32,
}

// Bisection rounds when clamping a move: 2^-16 of a step (CLAMP_ROUNDS of the CPU).
const CLAMP_ROUNDS: u32 = 16u;
const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: ProximityParams;
// Current positions, packed x, y, z: targets written in for the selection, as `collide` does.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> offsets: array<u32>;
@group(0) @binding(3) var<storage, read> entries: array<u32>;
// Faces first, four words each (a, b, c, layer); then from vertex_faces_base the vertex→faces
// rows: vertex_count + 1 absolute starts into this buffer, then the face ids.
@group(0) @binding(4) var<storage, read> topology: array<u32>;
@group(0) @binding(5) var<storage, read> moving: array<MovingVertex>;
@group(0) @binding(6) var<storage, read> rings: array<u32>;
// Per vertex: nonzero when it was pulled back in the last pass, so that its faces changed
// (the CPU's `changed` marks the faces around exactly those vertices).
@group(0) @binding(7) var<storage, read> marks: array<u32>;
@group(0) @binding(8) var<storage, read_write> pulled: array<PulledVertex>;

fn position(v: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}

// Whether the triangle abc touches the entry's exclusion ring. One pass without an early exit:
// a `return` inside this loop, inlined into the face loop, made Mesa 22.3's lavapipe skip
// later faces (tests/gpu_parity.rs, folded sheet).
fn touches_ring(entry: MovingVertex, a: u32, b: u32, c: u32) -> bool {
    var touches = false;
    for (var r = entry.ring_start; r < entry.ring_end; r++) {
        let w = rings[r];
        touches = touches || w == a || w == b || w == c;
    }
    return touches;
}

// The last safe fraction of the move against face f, or 1 when f does not constrain it.
fn safe_fraction(entry: MovingVertex, f: u32, x: vec3<f32>) -> f32 {
    let a = topology[4u * f];
    let b = topology[4u * f + 1u];
    let c = topology[4u * f + 2u];
    let layer = topology[4u * f + 3u];
    if params.all_faces == 0u && (marks[a] | marks[b] | marks[c]) == 0u {
        return 1.0;
    }
    let v = entry.vertex;
    if a == v || b == v || c == v {
        return 1.0;
    }
    // The vertex's own neighbourhood is near by construction, not by collision.
    if layer == entry.layer && touches_ring(entry, a, b, c) {
        return 1.0;
    }
    let pa = position(a);
    let pb = position(b);
    let pc = position(c);
    let d = params.distance;
    let here = distance_to_triangle(x, pa, pb, pc);
    if here >= d {
        return 1.0;
    }
    // Never closer than the collision distance, nor closer than it already was.
    let start = entry.start;
    let threshold = min(d, distance_to_triangle(start, pa, pb, pc));
    if here >= threshold {
        return 1.0;
    }
    // Distance along the move is convex and safe at its start: bisect over the whole move.
    var lo = 0.0;
    var hi = 1.0;
    for (var round = 0u; round < CLAMP_ROUNDS; round++) {
        let mid = 0.5 * (lo + hi);
        if distance_to_triangle(start + (x - start) * mid, pa, pb, pc) >= threshold {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i >= params.count {
        return;
    }
    let entry = moving[i];
    let x = position(entry.vertex);
    var t = 1.0;
    if any(x != entry.start) {
        // One flat loop over the box's cells, as `select` walks its box.
        let low = cell_of(x - vec3<f32>(params.cell_reach), params.inv_cell_size);
        let high = cell_of(x + vec3<f32>(params.cell_reach), params.inv_cell_size);
        let span = bitcast<vec3<u32>>(high - low) + vec3<u32>(1u);
        let cells = span.x * span.y * span.z;
        for (var n = 0u; n < cells; n++) {
            let step = vec3<u32>(n % span.x, (n / span.x) % span.y, n / (span.x * span.y));
            let bucket = hash_cell(low + bitcast<vec3<i32>>(step), params.table_mask);
            let end = offsets[bucket + 1u];
            for (var j = offsets[bucket]; j < end; j++) {
                let u = entries[j];
                if all(abs(position(u) - x) <= vec3<f32>(params.vertex_reach)) {
                    let row = params.vertex_faces_base + u;
                    let last = topology[row + 1u];
                    for (var k = topology[row]; k < last; k++) {
                        t = min(t, safe_fraction(entry, topology[k], x));
                    }
                }
            }
        }
    }
    var result = PulledVertex(x, 0u);
    if t < 1.0 {
        result = PulledVertex(entry.start + (x - entry.start) * t, 1u);
    }
    pulled[i] = result;
}
