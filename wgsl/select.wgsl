// Brush selection through the GPU hash table (sLayer Algorithm 2 "select"; docs/design.md, "A stroke"): the
// vertices of active layers, neither masked nor dead, within the brush sphere and with a
// positive falloff weight, appended to a compact list by an atomic counter.
//
// One invocation per grid cell of the brush's box: it walks the cell's bucket and keeps the
// vertices filed in that cell (other cells may share the bucket), so the work follows the
// brush, not the mesh. When the box has more cells than the mesh has vertices (a huge brush),
// the host sets `scan_vertices` and each invocation tests one vertex instead, as
// `SpatialHash::for_each_in_box` falls back to a scan. Each vertex is filed in one cell, so it
// is reported at most once; the list's order is the atomics' order.
//
// The table may be older than the positions: a backend rebuilds it only when vertices have
// drifted far (a rebuild costs a pass over the whole mesh; a step moves a few thousand
// vertices). Vertices are found in the cell of the position they were filed at (`hashed`),
// so the box is grown by `drift`, the farthest any vertex has moved since, and the sphere test
// reads the current position. Vertices remeshing changed (new ones among them) are filed in a
// small overlay table instead: the host runs the kernel over the main table with
// `skip_marked`, then over the overlay (src/gpu/overlay.rs).
// CPU mirror: src/cpu/select.rs.

#import shared/grid
#import shared/mesh
#import shared/brush

struct SelectParams {
    center: vec3<f32>,
    radius: f32,
    // Lowest cell of the brush's box and its size in cells.
    cell_min: vec3<i32>,
    table_mask: u32,
    cell_span: vec3<u32>,
    inv_cell_size: f32,
    // Cells in the box, or vertices when scanning.
    candidate_count: u32,
    scan_vertices: u32,
    falloff: u32,
    blend_n: u32,
    // Room in `selected`; the counter still counts past it, so the host sees an overflow.
    capacity: u32,
    layer_count: u32,
    // How far any vertex may have moved since the table was built (the box includes it).
    drift: f32,
    // Nonzero: leave out vertices with a nonzero `marks` entry (filed in another table, the
    // overlay of vertices remeshing changed; their entries in this one are stale).
    skip_marked: u32,
    // The blend's plateau, a share of the radius held at full strength.
    blend_inner: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: SelectParams;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> vertex_layers: array<u32>;
@group(0) @binding(3) var<storage, read> flags: array<u32>;
// Per layer: nonzero when the brush moves it.
@group(0) @binding(4) var<storage, read> active_layers: array<u32>;
@group(0) @binding(5) var<storage, read> offsets: array<u32>;
@group(0) @binding(6) var<storage, read> entries: array<u32>;
@group(0) @binding(7) var<storage, read_write> selected: array<SelectedVertex>;
@group(0) @binding(8) var<storage, read_write> selection_count: atomic<u32>;
// The positions the table was built from (packed x, y, z; may be `positions` itself).
@group(0) @binding(9) var<storage, read> hashed: array<f32>;
// Per vertex: nonzero when filed in the overlay table (read when `skip_marked` is set).
@group(0) @binding(10) var<storage, read> marks: array<u32>;

fn position(v: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}

fn consider(v: u32) {
    if (flags[v] & (VERTEX_MASKED | VERTEX_DEAD)) != 0u {
        return;
    }
    let layer = vertex_layers[v];
    if layer >= params.layer_count || active_layers[layer] == 0u {
        return;
    }
    let offset = position(v) - params.center;
    let distance_squared = dot(offset, offset);
    if distance_squared > params.radius * params.radius {
        return;
    }
    var weight = falloff_weight(params.falloff, params.blend_n, params.blend_inner, sqrt(distance_squared) / params.radius);
    // A partial mask (bits 8..15, 1 to 254 of 255) moves the vertex that much less; an exact
    // product of exact factors, as the mirror computes it.
    let mask_level = (flags[v] >> 8u) & 255u;
    if mask_level != 0u {
        weight *= f32(255u - mask_level) * MASK_STEP;
    }
    if weight <= 0.0 {
        return;
    }
    let slot = atomicAdd(&selection_count, 1u);
    if slot < params.capacity {
        selected[slot] = SelectedVertex(v, weight);
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) global_id: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
) {
    let candidate = flat_index(global_id, workgroups, WORKGROUP_SIZE);
    if candidate >= params.candidate_count {
        return;
    }
    if params.scan_vertices != 0u {
        consider(candidate);
        return;
    }
    let span = params.cell_span;
    let step = vec3<u32>(candidate % span.x, (candidate / span.x) % span.y, candidate / (span.x * span.y));
    let cell = params.cell_min + bitcast<vec3<i32>>(step);
    let bucket = hash_cell(cell, params.table_mask);
    let end = offsets[bucket + 1u];
    for (var j = offsets[bucket]; j < end; j++) {
        let v = entries[j];
        let filed_at = vec3<f32>(hashed[3u * v], hashed[3u * v + 1u], hashed[3u * v + 2u]);
        let elsewhere = params.skip_marked != 0u && marks[v] != 0u;
        if !elsewhere && all(cell_of(filed_at, params.inv_cell_size) == cell) {
            consider(v);
        }
    }
}
