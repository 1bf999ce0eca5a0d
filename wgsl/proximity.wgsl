// Vertex–triangle proximity and the collision response of one Jacobi pass (sLayer Algorithm 2
// "collide"; docs/design.md, "A stroke"): `pull_back` of src/collide/response.rs for every entry of the step's
// selection. An entry whose vertex sits at its start has nothing to test. Otherwise the vertex,
// at its tentative position x, is tested against every face near x outside its own
// neighbourhood, and where a face is closer than min(d, its distance from the start) the move
// is bisected for the last safe fraction; the result is the smallest fraction over all faces.
// Taking a minimum makes the result independent of the order faces are met in, and of meeting
// a face twice (through two of its vertices, or two cells sharing a bucket).
//
// One invocation per (entry, cell of the entry's box): it walks the cell's bucket and the faces
// of the vertices found, and folds its smallest fraction into the entry's slot of `pulls` with
// an atomic maximum of the pull-back amount (65536 − 65536·t: the bisection's fractions are
// multiples of 2⁻¹⁶, so the amount is exact; zero means not pulled). Short invocations keep the
// GPU busy whatever the reach, and stay far below the loop-iteration cap of Mesa's lavapipe,
// which counts every loop iteration of an invocation (65535 in all) and silently stops loops
// past it: one invocation walking a whole box of cells met it and skipped faces.
// `apply_moves` turns the amounts into positions.
// CPU mirror: src/cpu/proximity.rs.

#import shared/grid
#import shared/geom
#import shared/mesh
#import shared/moves
#import shared/pages
#paged topology 1
#paged ring_vertex 2

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
    vertex_rows_base: u32,
    // 1: test every face (the first pass); 0: only faces with a vertex marked in `marks`.
    all_faces: u32,
    // Cells per entry, from the cell of x − cell_reach: enough for any x (the host sizes it).
    span: vec3<u32>,
    cells_per_entry: u32,
    // Nonzero: vertices moved or changed since the table was built are filed in the overlay
    // table (src/gpu/overlay.rs, `overlay_mask + 1` buckets): each invocation walks its cell's
    // bucket there too, and leaves out of the main table's bucket the vertices marked in
    // `overlay_marks` (their entries there are stale).
    overlay: u32,
    overlay_mask: u32,
    _pad0: u32,
    _pad1: u32,
}

// Bisection rounds when clamping a move: 2^-16 of a step (CLAMP_ROUNDS of the CPU).
const CLAMP_ROUNDS: u32 = 16u;
// CLAMP_SLACK of src/abi/moves.rs: 1/65536.
const CLAMP_SLACK: f32 = 0.0000152587890625;
const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: ProximityParams;
// Current positions, packed x, y, z: targets written in for the selection, as `collide` does.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> offsets: array<u32>;
@group(0) @binding(3) var<storage, read> entries: array<u32>;
@group(0) @binding(4) var<storage, read> moving: array<MovingVertex>;
// Per vertex: nonzero when it was pulled back in the last pass, so that its faces changed
// (the CPU's `changed` marks the faces around exactly those vertices).
@group(0) @binding(5) var<storage, read> marks: array<u32>;
// Per entry: the largest pull-back amount found, 65536 − 65536·t; zero when not pulled.
@group(0) @binding(6) var<storage, read_write> pulls: array<atomic<u32>>;
// The overlay: per vertex nonzero when filed there, and its buckets (read when `overlay` is
// set).
@group(0) @binding(7) var<storage, read> overlay_marks: array<u32>;
@group(0) @binding(8) var<storage, read> overlay_offsets: array<u32>;
@group(0) @binding(9) var<storage, read> overlay_entries: array<u32>;
// Paged (shared/pages.wgsl), group 1: `topology(i)`, the packed topology
// (src/gpu/topology.rs): faces first, four words each (a, b, c, layer); then from
// vertex_rows_base per vertex the absolute start and length of its row of face ids
// (src/gpu/rows.rs), then the rows. Group 2: `ring_vertex(r)`, the exclusion rings of the entries, one
// after another (a moving vertex's ring can be some forty words: the largest per-entry array).

fn position(v: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}

// Whether the triangle abc touches the entry's exclusion ring. One pass without an early exit:
// a `return` inside this loop, inlined into the face loop, made Mesa 22.3's lavapipe skip
// later faces (tests/gpu_parity/proximity.rs, folded sheet).
fn touches_ring(entry: MovingVertex, a: u32, b: u32, c: u32) -> bool {
    var touches = false;
    for (var r = entry.ring_start; r < entry.ring_end; r++) {
        let w = ring_vertex(r);
        touches = touches || w == a || w == b || w == c;
    }
    return touches;
}

// The last safe fraction of the move against face f, or 1 when f does not constrain it.
// One exit (no early returns): see `touches_ring` and shared/geom.wgsl.
fn safe_fraction(entry: MovingVertex, f: u32, x: vec3<f32>) -> f32 {
    let a = topology(4u * f);
    let b = topology(4u * f + 1u);
    let c = topology(4u * f + 2u);
    let layer = topology(4u * f + 3u);
    let v = entry.vertex;
    // Faces the last pass left alone (unless it pulled this vertex back: short of its target
    // it can be nearer a face its move passed by), the vertex's own faces, and its own
    // neighbourhood (near by construction, not by collision) do not constrain it.
    let unchanged = params.all_faces == 0u && (marks[a] | marks[b] | marks[c] | marks[v]) == 0u;
    let own = a == v || b == v || c == v;
    let pa = position(a);
    let pb = position(b);
    let pc = position(c);
    let d = params.distance;
    // A face whose box is farther than d from x on some axis is farther than d: no closest
    // point needed (most faces the broad phase finds; the CPU filters by box too).
    let near = all(max(max(pa, pb), pc) >= x - vec3<f32>(d)) && all(min(min(pa, pb), pc) <= x + vec3<f32>(d));
    var t = 1.0;
    if near && !unchanged && !own && !(layer == entry.layer && touches_ring(entry, a, b, c)) {
        let here = distance_to_triangle(x, pa, pb, pc);
        // Never closer than the collision distance, nor closer than it already was, give or
        // take the slack (a move along the face must not stop on the arithmetic's last bits).
        let start = entry.start;
        if here < d {
            let threshold = min(d, distance_to_triangle(start, pa, pb, pc));
            if here < threshold - CLAMP_SLACK * d {
                // Distance along the move is convex and safe at its start: bisect over the
                // whole move.
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
                t = lo;
            }
        }
    }
    return t;
}

// Bisection fractions are multiples of 1 / PULL_SCALE.
const PULL_SCALE: f32 = 65536.0;

// The smallest safe fraction against the faces of vertex u, if u is within reach of x.
fn faces_fraction(entry: MovingVertex, u: u32, x: vec3<f32>) -> f32 {
    var t = 1.0;
    if all(abs(position(u) - x) <= vec3<f32>(params.vertex_reach)) {
        let row = params.vertex_rows_base + 2u * u;
        let first = topology(row);
        let last = first + topology(row + 1u);
        for (var k = first; k < last; k++) {
            t = min(t, safe_fraction(entry, topology(k), x));
        }
    }
    return t;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i >= params.count * params.cells_per_entry {
        return;
    }
    let e = i / params.cells_per_entry;
    let n = i % params.cells_per_entry;
    let entry = moving[e];
    // A vacant entry (shared/moves) stays at its start: it tests nothing.
    var x = entry.start;
    if entry.vertex != INVALID {
        x = position(entry.vertex);
    }
    var t = 1.0;
    if any(x != entry.start) {
        let low = cell_of(x - vec3<f32>(params.cell_reach), params.inv_cell_size);
        let span = params.span;
        let step = vec3<u32>(n % span.x, (n / span.x) % span.y, n / (span.x * span.y));
        let cell = low + bitcast<vec3<i32>>(step);
        let bucket = hash_cell(cell, params.table_mask);
        let end = offsets[bucket + 1u];
        for (var j = offsets[bucket]; j < end; j++) {
            let u = entries[j];
            if params.overlay == 0u || overlay_marks[u] == 0u {
                t = min(t, faces_fraction(entry, u, x));
            }
        }
        if params.overlay != 0u {
            let b = hash_cell(cell, params.overlay_mask);
            let last = overlay_offsets[b + 1u];
            for (var j = overlay_offsets[b]; j < last; j++) {
                t = min(t, faces_fraction(entry, overlay_entries[j], x));
            }
        }
    }
    if t < 1.0 {
        atomicMax(&pulls[e], 65536u - u32(t * PULL_SCALE));
    }
}
