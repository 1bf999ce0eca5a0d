// The preview renderer (docs/design.md, "Materials and rendering"): per-vertex BRDFs shaded with the microfacet model of
// `shared/brdf`, a key and a fill light, an optional wireframe and per-layer false colours.
// Host side: src/render/preview.rs.
//
// Vertices are pulled from storage buffers by `vertex_index` (three per face, no index buffer),
// so each corner knows which corner of its triangle it is: that gives the barycentric
// coordinates the wireframe needs without duplicating the mesh's vertices.
//
// `vs_main` reads whole rows from `vertices`. `vs_engine` (the app, when it shares the GPU
// backend's device) reads positions and normals from the backend's own per-vertex buffers and
// only the rest of each row from `vertices`, so a sculpting stroke uploads nothing to draw.

#import shared/brdf

struct RenderVertex {
    position: vec3<f32>,
    layer: u32,
    normal: vec3<f32>,
    roughness: f32,
    diffuse: vec3<f32>,
    // The sculpting mask, 0..1 (shown as a dark tint when `show_mask` is 1).
    mask: f32,
    specular: vec3<f32>,
    _pad1: f32,
}

const PALETTE_SIZE: u32 = 8u;

struct PreviewUniforms {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    key_direction: vec4<f32>,
    key_irradiance: vec4<f32>,
    fill_direction: vec4<f32>,
    fill_irradiance: vec4<f32>,
    sky: vec4<f32>,
    ground: vec4<f32>,
    // 1 to draw edges.
    wireframe: u32,
    // 1 to replace every layer's diffuse albedo by its palette colour.
    false_colour: u32,
    // Edge line width in pixels.
    line_width: f32,
    // Bit `l` set: layer `l` (< 32) is not drawn (the app's per-layer visibility).
    hidden_layers: u32,
    // 1 to darken masked vertices.
    show_mask: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    palette: array<vec4<f32>, PALETTE_SIZE>,
}

@group(0) @binding(0) var<uniform> view: PreviewUniforms;
@group(0) @binding(1) var<storage, read> vertices: array<RenderVertex>;
// Three vertex numbers per face, into `vertices`.
@group(0) @binding(2) var<storage, read> corners: array<u32>;

struct Varyings {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) diffuse: vec3<f32>,
    @location(3) specular: vec3<f32>,
    @location(4) roughness: f32,
    @location(5) barycentric: vec3<f32>,
    @location(6) @interpolate(flat) layer: u32,
    @location(7) mask: f32,
}

// The GPU backend's positions and normals: x, y, z per vertex, packed (`src/gpu/vertices.rs`,
// `src/gpu/backend/resident.rs`).
// Bound only by the pipeline whose vertex stage is `vs_engine`.
@group(0) @binding(3) var<storage, read> engine_positions: array<f32>;
@group(0) @binding(4) var<storage, read> engine_normals: array<f32>;

fn corner_varyings(index: u32, vertex: RenderVertex) -> Varyings {
    var out: Varyings;
    out.clip = view.view_proj * vec4<f32>(vertex.position, 1.0);
    out.world = vertex.position;
    out.normal = vertex.normal;
    out.diffuse = vertex.diffuse;
    out.specular = vertex.specular;
    out.roughness = vertex.roughness;
    let corner = index % 3u;
    out.barycentric = vec3<f32>(f32(corner == 0u), f32(corner == 1u), f32(corner == 2u));
    out.layer = vertex.layer;
    out.mask = vertex.mask;
    if vertex.layer < 32u && (view.hidden_layers & (1u << vertex.layer)) != 0u {
        // Behind the near plane: the whole triangle is clipped.
        out.clip = vec4<f32>(0.0, 0.0, -1.0, 1.0);
    }
    return out;
}

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> Varyings {
    return corner_varyings(index, vertices[corners[index]]);
}

@vertex
fn vs_engine(@builtin(vertex_index) index: u32) -> Varyings {
    let v = corners[index];
    var vertex = vertices[v];
    vertex.position = vec3<f32>(
        engine_positions[3u * v], engine_positions[3u * v + 1u], engine_positions[3u * v + 2u]
    );
    let normal = vec3<f32>(
        engine_normals[3u * v], engine_normals[3u * v + 1u], engine_normals[3u * v + 2u]
    );
    // As `render_vertex` does on the CPU: a normal that is not finite is drawn as none (the
    // fragment stage then takes the face's). Told by the exponent bits: a shader compiler may
    // assume that no float is NaN and fold a comparison away.
    let exponent = vec3<u32>(0x7f800000u);
    let finite = all((bitcast<vec3<u32>>(normal) & exponent) != exponent);
    vertex.normal = select(vec3<f32>(0.0), normal, finite);
    return corner_varyings(index, vertex);
}

@fragment
fn fs_main(in: Varyings) -> @location(0) vec4<f32> {
    // Interpolated BRDFs are in-between materials: the parametrization is linear.
    var brdf = Brdf(in.diffuse, in.specular, in.roughness);
    if view.false_colour != 0u {
        brdf.diffuse = view.palette[in.layer % PALETTE_SIZE].xyz;
    }
    // Derivatives are taken before any branch that depends on the fragment.
    let geometric = cross(dpdx(in.world), dpdy(in.world));
    let edge_width = fwidth(in.barycentric);
    var n = in.normal;
    let v = normalize(view.eye.xyz - in.world);
    if dot(n, n) < 1e-12 {
        n = geometric;
    }
    if dot(n, n) < 1e-20 {
        n = v;
    }
    n = normalize(n);
    let key = Light(view.key_direction.xyz, view.key_irradiance.xyz);
    let fill = Light(view.fill_direction.xyz, view.fill_irradiance.xyz);
    let env = Environment(view.sky.xyz, view.ground.xyz);
    var colour = shade(brdf, n, v, key, fill, env);
    if view.show_mask != 0u {
        colour = mix(colour, vec3<f32>(0.03, 0.03, 0.04), 0.7 * clamp(in.mask, 0.0, 1.0));
    }
    if view.wireframe != 0u {
        let distance_in_pixels = in.barycentric / max(edge_width, vec3<f32>(1e-6));
        let nearest = min(min(distance_in_pixels.x, distance_in_pixels.y), distance_in_pixels.z);
        let line = 1.0 - smoothstep(0.0, view.line_width, nearest);
        colour = mix(colour, vec3<f32>(0.02, 0.02, 0.03), 0.75 * line);
    }
    return vec4<f32>(colour, 1.0);
}
