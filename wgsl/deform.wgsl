// Brush deformation (sLayer Algorithm 2 "deform"; docs/design.md, "A stroke"): the target position of every
// selected vertex under the dab's field, as `src/brush/field.rs::displacement` computes it.
// One invocation per selection entry; `targets[i]` belongs to `selected[i]`. Non-finite
// targets (absurd input) leave the vertex where it is, as on the CPU.
// The dab's normal and plane point come from the parameters, or (`frame` flags) from the sums
// `brush_frame` left in `frame_sums` in the same submission, so that selection, frame and
// deformation need no read-back between them.
// CPU mirror: src/cpu/deform.rs.

#import shared/grid
#import shared/brush
#import shared/pages
#import shared/fixed
#import shared/order_free
#paged neighbour 1

struct DeformParams {
    center: vec3<f32>,
    radius: f32,
    // Unit brush normal.
    normal: vec3<f32>,
    strength: f32,
    // Flatten's and trim's plane point.
    plane_point: vec3<f32>,
    pressure: f32,
    // Grab's and the sweeps' motion of the brush centre.
    motion: vec3<f32>,
    // Share of the sample this step carries (1 / steps).
    share: f32,
    // A BRUSH_* code.
    kind: u32,
    // +1, or -1 when inverted (deflate is inflate inverted).
    sign: f32,
    // Entries in `selected` (its capacity): invocations past the selection count return.
    capacity: u32,
    // FRAME_* flags: which of normal and plane point come from `frame_sums`.
    frame: u32,
}

// As src/gpu/deform.rs writes them.
const FRAME_PLANE_FROM_SUMS: u32 = 1u;
const FRAME_NORMAL_FROM_SUMS: u32 = 2u;

// As in src/brush/field.rs.
const DRAW_RATE: f32 = 0.1;
const PINCH_RATE: f32 = 0.25;
const TWIST_RATE: f32 = 0.5;
const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: DeformParams;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> selected: array<SelectedVertex>;
@group(0) @binding(4) var<storage, read> selection_count: u32;
// Smooth's neighbours (src/gpu/rows.rs): vertex v averages neighbour(j) for the
// neighbour_rows[2v + 1] words j from neighbour_rows[2v] (its one-ring in fan order; on a
// boundary only its two boundary neighbours).
@group(0) @binding(5) var<storage, read> neighbour_rows: array<u32>;
// Packed x, y, z per selection entry.
@group(0) @binding(6) var<storage, read_write> targets: array<f32>;
// brush_frame's fixed-point sums (read only where `params.frame` asks).
@group(0) @binding(7) var<storage, read> frame_sums: array<u32, 24>;
// Paged (shared/pages.wgsl), group 1: `neighbour(j)`, the neighbour lists (about six words a
// vertex: the largest per-vertex array).

// The parameters with the frame resolved: what every brush below reads.
var<private> dab: DeformParams;

fn frame_sum(k: u32) -> f32 {
    return from_fixed(vec3<u32>(frame_sums[3u * k], frame_sums[3u * k + 1u], frame_sums[3u * k + 2u]));
}

// As src/cpu/brush_frame.rs::frame_from_sums: the normalized normal sum (the parameters'
// normal when it has no direction), and the weighted mean offset scaled back about the centre
// (the centre when no weight).
fn resolve_frame() {
    dab = params;
    if (params.frame & FRAME_NORMAL_FROM_SUMS) != 0u {
        let sum = vec3<f32>(frame_sum(0u), frame_sum(1u), frame_sum(2u));
        let length_squared = sum.x * sum.x + sum.y * sum.y + sum.z * sum.z;
        // Below 1e-30 the normals cancel out (and squares that small near the denormals GPUs
        // flush): the parameters' normal stands.
        if length_squared >= 1e-30 && length_squared <= 3.40282347e38 {
            dab.normal = sum * (1.0 / sqrt(length_squared));
        }
    }
    if (params.frame & FRAME_PLANE_FROM_SUMS) != 0u {
        let weight = frame_sum(6u);
        dab.plane_point = params.center;
        if weight > 0.0 {
            let offset = vec3<f32>(frame_sum(3u), frame_sum(4u), frame_sum(5u));
            dab.plane_point = params.center + offset / weight * params.radius;
        }
    }
}

fn position(v: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}

// The centroid of v's neighbours: their offsets from p summed order-free, as the pipeline's
// `ring_centroid`; p itself where there are none or an offset is not finite.
fn ring_centroid(v: u32, p: vec3<f32>) -> vec3<f32> {
    let start = neighbour_rows[2u * v];
    let end = start + neighbour_rows[2u * v + 1u];
    var largest = 0.0;
    for (var j = start; j < end; j++) {
        let offset = position(neighbour(j)) - p;
        if !order_free_finite(offset) {
            return p;
        }
        largest = max(largest, order_free_largest(offset));
    }
    if largest < ORDER_FREE_MIN_F32 {
        return p;
    }
    let exponent = order_free_exponent(largest, end - start);
    var sum = vec3<i32>(0);
    for (var j = start; j < end; j++) {
        sum += order_free_term(position(neighbour(j)) - p, exponent);
    }
    return p + order_free_value(sum, exponent) / f32(end - start);
}

fn pinch(p: vec3<f32>) -> vec3<f32> {
    let to_center = dab.center - p;
    let tangential = to_center - dab.normal * dot(to_center, dab.normal);
    return tangential * PINCH_RATE;
}

// `v` rotated by the unit quaternion (axis * sin(a/2), cos(a/2)), in glam's order of operations.
fn rotate(axis: vec3<f32>, angle: f32, v: vec3<f32>) -> vec3<f32> {
    let half = angle * 0.5;
    let b = axis * sin(half);
    let w = cos(half);
    let b2 = dot(b, b);
    return v * (w * w - b2) + b * (dot(v, b) * 2.0) + cross(b, v) * (w * 2.0);
}

fn displacement(v: u32, p: vec3<f32>, weight: f32) -> vec3<f32> {
    let amount = dab.strength * dab.pressure * weight * dab.share;
    let sign = dab.sign;
    let lift = sign * amount * DRAW_RATE * dab.radius;
    switch dab.kind {
        case BRUSH_DRAW: {
            return dab.normal * lift;
        }
        case BRUSH_INFLATE, BRUSH_DEFLATE: {
            let n = vec3<f32>(normals[3u * v], normals[3u * v + 1u], normals[3u * v + 2u]);
            return n * lift;
        }
        case BRUSH_GRAB, BRUSH_SWEEP, BRUSH_SWEEP_VOLUME: {
            return dab.motion * (weight * dab.share);
        }
        case BRUSH_SMOOTH: {
            return (ring_centroid(v, p) - p) * min(amount, 1.0);
        }
        case BRUSH_FLATTEN: {
            let height = dot(p - dab.plane_point, dab.normal);
            var pull = 0.5 * height;
            if sign > 0.0 {
                pull = -height;
            }
            return dab.normal * (pull * min(amount, 1.0));
        }
        case BRUSH_TRIM: {
            // Only what stands above the plane (inverted: lies below it) moves to it.
            let height = dot(p - dab.plane_point, dab.normal);
            var standing = max(height, 0.0);
            if sign < 0.0 {
                standing = min(height, 0.0);
            }
            return dab.normal * (-standing * min(amount, 1.0));
        }
        case BRUSH_PINCH: {
            return pinch(p) * (sign * amount);
        }
        case BRUSH_CREASE: {
            return -dab.normal * lift + pinch(p) * amount;
        }
        case BRUSH_TWIST: {
            let turned = rotate(dab.normal, sign * amount * TWIST_RATE, p - dab.center);
            return dab.center + turned - p;
        }
        default: {
            return vec3<f32>(0.0);
        }
    }
}

// WGSL has no isfinite: NaN fails every comparison and infinities exceed the largest float.
fn is_finite(q: vec3<f32>) -> bool {
    return all(abs(q) <= vec3<f32>(3.40282347e38));
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let i = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if i >= min(selection_count, params.capacity) {
        return;
    }
    resolve_frame();
    let entry = selected[i];
    let p = position(entry.vertex);
    var q = p + displacement(entry.vertex, p, entry.weight);
    if !is_finite(q) {
        q = p;
    }
    targets[3u * i] = q.x;
    targets[3u * i + 1u] = q.y;
    targets[3u * i + 2u] = q.z;
}
