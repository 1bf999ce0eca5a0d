// The exact backstop's filter (docs/design.md, "A stroke"; phase B of `collide_with` in src/collide/response.rs).
// After the proximity passes, no face a step moved may cross another face, nor turn over, nor
// fold onto a face it shares a vertex with. Deciding that exactly takes the CPU's predicates;
// this kernel settles the many pairs that are plainly apart in f32, with margins far above
// its rounding (2^-12 of the pair's size, against some 2^-21 of error), and lists the rest —
// the undecided pairs — for the CPU. So the CPU neither gathers the step's region nor searches
// it: it decides a handful of pairs, and the crossings it finds are exactly those its own
// search would have found.
//
// A face moved when one of its vertices did (`moved`: the entry + 1 of vertices the step
// moved, zero elsewhere); it is tested by the entry of its lowest-numbered moved vertex. Its
// pairs:
// - (f, f) when f may have turned over: its normal from the start positions against now;
// - (f, g) for g sharing a vertex with f, when the two may overlap beyond what they share;
// - (f, g) for g sharing none, when their boxes overlap and no separating axis clears them.
// A face g crossing f has every vertex within two longest edges of f's moved vertex x, its
// lowest-numbered one too: g is met once, through that vertex, in the cells around x. Where
// both faces moved, the pair is tested from the lower face only, as the CPU does.
//
// One invocation per (entry, row of cells along x of the box around the entry's vertex); the
// first row's also tests the neighbours. Cells farther than an edge from every face the entry
// tests are skipped (most of the box: it must reach two edges around the vertex). Pairs are appended to `pairs` (two words each) up to `capacity`;
// `pair_count` counts them all, so the host sees an overflow and searches on the CPU instead.
// CPU mirror: src/cpu/backstop.rs.

#import shared/grid
#import shared/mesh
#import shared/moves
#import shared/pages
#paged topology 1

struct BackstopParams {
    // Cells searched: those of the box x ± cell_reach, x the moved vertex's position. It must
    // cover the hashed position of every vertex within `vertex_reach` of x: that reach plus
    // how far any vertex has moved since the table was built.
    cell_reach: f32,
    // Two longest edges (after the step's moves): bucket entries farther than this from x on
    // some axis are skipped.
    vertex_reach: f32,
    inv_cell_size: f32,
    table_mask: u32,
    // Entries in `moving`.
    count: u32,
    // Where the vertex→faces rows start in `topology`.
    vertex_rows_base: u32,
    // Invocations per entry: rows of cells, span.y · span.z.
    cells_per_entry: u32,
    // Room in `pairs`, in pairs.
    capacity: u32,
    // Cells of the entry's box (x, y, z), from the cell of x − cell_reach; an invocation walks
    // one row along x, so there are span.y · span.z per entry.
    span: vec3<u32>,
    // Nonzero: the overlay table is walked too (as in proximity.wgsl).
    overlay: u32,
    overlay_mask: u32,
    // One longest edge (after the step's moves) plus how far any vertex may be from where it
    // is filed: a cell farther than this from every face the entry tests holds no vertex of a
    // face crossing one of them, and is skipped.
    face_reach: f32,
    _pad1: u32,
    _pad2: u32,
}

// Share of a pair's size below which a separation is not trusted: 2^-12.
const MARGIN: f32 = 0.000244140625;
const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: BackstopParams;
// Positions after the proximity passes, packed x, y, z.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> offsets: array<u32>;
@group(0) @binding(3) var<storage, read> entries: array<u32>;
@group(0) @binding(4) var<storage, read> moving: array<MovingVertex>;
// Per vertex: the index + 1 of its entry in `moving` when the step moved it, else zero.
@group(0) @binding(5) var<storage, read> moved: array<u32>;
// Undecided pairs (f, g), two words each.
@group(0) @binding(6) var<storage, read_write> pairs: array<u32>;
@group(0) @binding(7) var<storage, read_write> pair_count: atomic<u32>;
@group(0) @binding(8) var<storage, read> overlay_marks: array<u32>;
@group(0) @binding(9) var<storage, read> overlay_offsets: array<u32>;
@group(0) @binding(10) var<storage, read> overlay_entries: array<u32>;
// Paged, group 1: `topology(i)`, the packed topology (src/gpu/topology.rs), as proximity.wgsl
// reads it.

fn position(v: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}

// Where v was at the step's start.
fn old_position(v: u32) -> vec3<f32> {
    let entry = moved[v];
    var p = position(v);
    if entry != 0u {
        p = moving[entry - 1u].start;
    }
    return p;
}

fn face(f: u32) -> vec3<u32> {
    return vec3<u32>(topology(4u * f), topology(4u * f + 1u), topology(4u * f + 2u));
}

fn is_moved(v: u32) -> bool {
    return moved[v] != 0u;
}

fn is_moving(t: vec3<u32>) -> bool {
    return is_moved(t.x) || is_moved(t.y) || is_moved(t.z);
}

// Whether moved vertex v is the lowest-numbered moved vertex of face t: the one entry that
// tests t.
fn tests_face(v: u32, t: vec3<u32>) -> bool {
    var mine = true;
    for (var k = 0u; k < 3u; k++) {
        let w = t[k];
        mine = mine && (w == v || !is_moved(w) || v < w);
    }
    return mine;
}

fn shared_vertices(s: vec3<u32>, t: vec3<u32>) -> u32 {
    var count = 0u;
    for (var k = 0u; k < 3u; k++) {
        count += u32(s[k] == t.x || s[k] == t.y || s[k] == t.z);
    }
    return count;
}

fn max_abs(p: vec3<f32>) -> f32 {
    let a = abs(p);
    return max(max(a.x, a.y), a.z);
}

fn append(f: u32, g: u32) {
    let slot = atomicAdd(&pair_count, 1u);
    if slot < params.capacity {
        pairs[2u * slot] = f;
        pairs[2u * slot + 1u] = g;
    }
}

// Whether `axis` separates triangles a and b (coordinates at most about 1) by more than the
// margin. A zero or non-finite axis separates nothing.
fn separates(axis: vec3<f32>, a0: vec3<f32>, a1: vec3<f32>, a2: vec3<f32>, b0: vec3<f32>, b1: vec3<f32>, b2: vec3<f32>) -> bool {
    let margin = MARGIN * sqrt(dot(axis, axis));
    let pa = vec3<f32>(dot(a0, axis), dot(a1, axis), dot(a2, axis));
    let pb = vec3<f32>(dot(b0, axis), dot(b1, axis), dot(b2, axis));
    let a_lo = min(min(pa.x, pa.y), pa.z);
    let a_hi = max(max(pa.x, pa.y), pa.z);
    let b_lo = min(min(pb.x, pb.y), pb.z);
    let b_hi = max(max(pb.x, pb.y), pb.z);
    return margin > 0.0 && (a_hi + margin < b_lo || b_hi + margin < a_lo);
}

// `surely_disjoint` of src/geom/separation.rs in f32: the separating axis test (both normals,
// the nine edge pairs, the six in-plane edge normals), the pair moved to a's first corner and
// scaled to coordinates of at most 1 so that the margin is relative and nothing underflows.
fn surely_apart(a: array<vec3<f32>, 3>, b: array<vec3<f32>, 3>) -> bool {
    let o = a[0];
    let scale = max(max(max_abs(a[1] - o), max_abs(a[2] - o)), max(max(max_abs(b[0] - o), max_abs(b[1] - o)), max_abs(b[2] - o)));
    let s = 1.0 / scale;
    let a0 = vec3<f32>(0.0);
    let a1 = (a[1] - o) * s;
    let a2 = (a[2] - o) * s;
    let b0 = (b[0] - o) * s;
    let b1 = (b[1] - o) * s;
    let b2 = (b[2] - o) * s;
    var ea = array<vec3<f32>, 3>(a1 - a0, a2 - a1, a0 - a2);
    var eb = array<vec3<f32>, 3>(b1 - b0, b2 - b1, b0 - b2);
    let na = cross(ea[0], ea[1]);
    let nb = cross(eb[0], eb[1]);
    var apart = separates(na, a0, a1, a2, b0, b1, b2) || separates(nb, a0, a1, a2, b0, b1, b2);
    for (var i = 0u; i < 3u; i++) {
        for (var j = 0u; j < 3u; j++) {
            apart = apart || separates(cross(ea[i], eb[j]), a0, a1, a2, b0, b1, b2);
        }
        apart = apart || separates(cross(na, ea[i]), a0, a1, a2, b0, b1, b2);
        apart = apart || separates(cross(na, eb[i]), a0, a1, a2, b0, b1, b2);
    }
    return apart;
}

// `surely_apart_at_shared_vertex` of src/geom/separation.rs in f32, scaled as above: the
// wedges at p, seen along a direction both triangles face, on either side of a line.
fn apart_at_shared_vertex(p: vec3<f32>, a1: vec3<f32>, a2: vec3<f32>, b1: vec3<f32>, b2: vec3<f32>) -> bool {
    let scale = max(max(max_abs(a1 - p), max_abs(a2 - p)), max(max_abs(b1 - p), max_abs(b2 - p)));
    let s = 1.0 / scale;
    let u1 = (a1 - p) * s;
    let u2 = (a2 - p) * s;
    let w1 = (b1 - p) * s;
    let w2 = (b2 - p) * s;
    let na = cross(u1, u2);
    let nb = cross(w1, w2);
    let view = na * dot(nb, nb) + nb * dot(na, na);
    let margin = MARGIN * max_abs(view);
    let faces_view = dot(na, view) > margin && dot(nb, view) > margin;
    let s11 = dot(cross(u1, w1), view);
    let s12 = dot(cross(u1, w2), view);
    let s21 = dot(cross(u2, w1), view);
    let s22 = dot(cross(u2, w2), view);
    return faces_view && ((s11 < -margin && s12 < -margin) || (s21 > margin && s22 > margin) || (s11 > margin && s21 > margin) || (s12 < -margin && s22 < -margin));
}

// Triangles sharing the edge pq, with far corners a and b, lie on either side of it: then they
// overlap nowhere else (`neighbours_overlap` finds overlap only for coplanar pairs on one side).
fn apart_across_edge(p: vec3<f32>, q: vec3<f32>, a: vec3<f32>, b: vec3<f32>) -> bool {
    let scale = max(max_abs(q - p), max(max_abs(a - p), max_abs(b - p)));
    let s = 1.0 / scale;
    let e = (q - p) * s;
    let ca = cross(e, (a - p) * s);
    let cb = cross(e, (b - p) * s);
    return dot(ca, cb) < -MARGIN;
}

// Whether faces f and g, sharing one or two vertices, may overlap beyond them.
fn neighbours_undecided(tf: vec3<u32>, tg: vec3<u32>) -> bool {
    var undecided = true;
    // Corners of f then g, turned so that the shared ones come first.
    var shared_f = 0u;
    var shared_g = 0u;
    var count = 0u;
    for (var i = 0u; i < 3u; i++) {
        for (var j = 0u; j < 3u; j++) {
            if tf[i] == tg[j] && count == 0u {
                shared_f = i;
                shared_g = j;
            }
            count += u32(tf[i] == tg[j]);
        }
    }
    if count == 1u {
        let p = position(tf[shared_f]);
        undecided = !apart_at_shared_vertex(p, position(tf[(shared_f + 1u) % 3u]), position(tf[(shared_f + 2u) % 3u]), position(tg[(shared_g + 1u) % 3u]), position(tg[(shared_g + 2u) % 3u]));
    } else if count == 2u {
        var far_f = 0u;
        var far_g = 0u;
        for (var k = 0u; k < 3u; k++) {
            if tf[k] != tg.x && tf[k] != tg.y && tf[k] != tg.z {
                far_f = k;
            }
            if tg[k] != tf.x && tg[k] != tf.y && tg[k] != tf.z {
                far_g = k;
            }
        }
        undecided = !apart_across_edge(position(tf[(far_f + 1u) % 3u]), position(tf[(far_f + 2u) % 3u]), position(tf[far_f]), position(tg[far_g]));
    }
    return undecided;
}

// Whether f may have turned over in the step: its normals before and after do not surely
// point the same way.
fn may_turn_over(t: vec3<u32>) -> bool {
    let o0 = old_position(t.x);
    let o1 = old_position(t.y) - o0;
    let o2 = old_position(t.z) - o0;
    let p0 = position(t.x);
    let p1 = position(t.y) - p0;
    let p2 = position(t.z) - p0;
    let so = 1.0 / max(max_abs(o1), max_abs(o2));
    let sp = 1.0 / max(max_abs(p1), max_abs(p2));
    let before = cross(o1 * so, o2 * so);
    let after = cross(p1 * sp, p2 * sp);
    return !(dot(before, after) > MARGIN);
}

// The faces of v that v tests, against their neighbours; and whether each turned over.
fn test_neighbours(v: u32, first: u32, last: u32) {
    for (var k = first; k < last; k++) {
        let f = topology(k);
        let tf = face(f);
        if tests_face(v, tf) {
            if may_turn_over(tf) {
                append(f, f);
            }
            for (var c = 0u; c < 3u; c++) {
                let row = params.vertex_rows_base + 2u * tf[c];
                let start = topology(row);
                let end = start + topology(row + 1u);
                for (var kg = start; kg < end; kg++) {
                    let g = topology(kg);
                    let tg = face(g);
                    if g != f && !(g < f && is_moving(tg)) && neighbours_undecided(tf, tg) {
                        append(f, g);
                    }
                }
            }
        }
    }
}

// The faces of v that v tests, against the faces g of bucket vertex u that are met through
// it (u is g's lowest-numbered vertex) and share no vertex with them.
fn test_vertex(v: u32, first: u32, last: u32, u: u32, x: vec3<f32>) {
    if all(abs(position(u) - x) <= vec3<f32>(params.vertex_reach)) {
        let row = params.vertex_rows_base + 2u * u;
        let start = topology(row);
        let end = start + topology(row + 1u);
        for (var kg = start; kg < end; kg++) {
            let g = topology(kg);
            let tg = face(g);
            if u == min(min(tg.x, tg.y), tg.z) {
                let b = array<vec3<f32>, 3>(position(tg.x), position(tg.y), position(tg.z));
                let b_lo = min(min(b[0], b[1]), b[2]);
                let b_hi = max(max(b[0], b[1]), b[2]);
                for (var k = first; k < last; k++) {
                    let f = topology(k);
                    let tf = face(f);
                    if tests_face(v, tf) && shared_vertices(tf, tg) == 0u && !(g < f && is_moving(tg)) {
                        let a = array<vec3<f32>, 3>(position(tf.x), position(tf.y), position(tf.z));
                        let overlap = all(max(max(a[0], a[1]), a[2]) >= b_lo) && all(min(min(a[0], a[1]), a[2]) <= b_hi);
                        if overlap && !surely_apart(a, b) {
                            append(f, g);
                        }
                    }
                }
            }
        }
    }
}

// The faces of the vertices filed in `cell`, main table and overlay.
fn test_cell(v: u32, first: u32, last: u32, cell: vec3<i32>, x: vec3<f32>) {
    let bucket = hash_cell(cell, params.table_mask);
    let end = offsets[bucket + 1u];
    for (var j = offsets[bucket]; j < end; j++) {
        let u = entries[j];
        if params.overlay == 0u || overlay_marks[u] == 0u {
            test_vertex(v, first, last, u, x);
        }
    }
    if params.overlay != 0u {
        let b = hash_cell(cell, params.overlay_mask);
        let last_entry = overlay_offsets[b + 1u];
        for (var j = overlay_offsets[b]; j < last_entry; j++) {
            test_vertex(v, first, last, overlay_entries[j], x);
        }
    }
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
    let v = moving[e].vertex;
    // Vacant entries (shared/moves) moved nothing.
    if v == INVALID || !is_moved(v) {
        return;
    }
    let x = position(v);
    let row = params.vertex_rows_base + 2u * v;
    let first = topology(row);
    let last = first + topology(row + 1u);
    if n == 0u {
        test_neighbours(v, first, last);
    }
    // The box of the faces the entry tests: most cells of the entry's box are too far from it.
    var lo = x;
    var hi = x;
    var tests_any = false;
    for (var k = first; k < last; k++) {
        let t = face(topology(k));
        if tests_face(v, t) {
            tests_any = true;
            lo = min(lo, min(min(position(t.x), position(t.y)), position(t.z)));
            hi = max(hi, max(max(position(t.x), position(t.y)), position(t.z)));
        }
    }
    let reach = vec3<f32>(params.face_reach);
    let near_lo = cell_of(lo - reach, params.inv_cell_size);
    let near_hi = cell_of(hi + reach, params.inv_cell_size);
    let low = cell_of(x - vec3<f32>(params.cell_reach), params.inv_cell_size);
    let span = params.span;
    let row_cell = low + bitcast<vec3<i32>>(vec3<u32>(0u, n % span.y, n / span.y));
    let near_row = all(row_cell.yz >= near_lo.yz) && all(row_cell.yz <= near_hi.yz);
    if tests_any && near_row {
        for (var step = 0u; step < span.x; step++) {
            let cell = row_cell + vec3<i32>(i32(step), 0, 0);
            if cell.x >= near_lo.x && cell.x <= near_hi.x {
                test_cell(v, first, last, cell, x);
            }
        }
    }
}
