// The preview's reflectance model: Cook–Torrance with the normalized Blinn–Phong distribution,
// Schlick's Fresnel and Cook and Torrance's V-cavity shadowing, over the linear BRDF
// parametrization (diffuse albedo, specular albedo, linearized roughness).
// Mirrors `src/render/brdf.rs` function for function; see there for why roughness maps to the
// exponent this way.

const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717959;
// Smallest microfacet slope rendered (`MIN_SLOPE`).
const MIN_SLOPE: f32 = 0.03;

struct Brdf {
    diffuse: vec3<f32>,
    specular: vec3<f32>,
    roughness: f32,
}

struct Light {
    direction: vec3<f32>,
    irradiance: vec3<f32>,
}

fn blinn_exponent(roughness: f32) -> f32 {
    let r = clamp(roughness, 0.0, 1.0);
    let alpha = max(r * r, MIN_SLOPE);
    return 2.0 / (alpha * alpha) - 2.0;
}

fn blinn_distribution(n_dot_h: f32, exponent: f32) -> f32 {
    return (exponent + 2.0) / TAU * pow(max(n_dot_h, 0.0), exponent);
}

fn schlick_fresnel(f0: vec3<f32>, v_dot_h: f32) -> vec3<f32> {
    let m = pow(1.0 - clamp(v_dot_h, 0.0, 1.0), 5.0);
    return f0 + (vec3<f32>(1.0) - f0) * m;
}

fn shadowing(n_dot_l: f32, n_dot_v: f32, n_dot_h: f32, v_dot_h: f32) -> f32 {
    let g = 2.0 * n_dot_h / max(v_dot_h, 1e-4);
    return min(min(g * n_dot_v, g * n_dot_l), 1.0);
}

// f(l, v)·(n·l) for unit vectors, `n` facing the viewer.
fn reflect_light(brdf: Brdf, n: vec3<f32>, l: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let n_dot_l = dot(n, l);
    if n_dot_l <= 0.0 {
        return vec3<f32>(0.0);
    }
    let n_dot_v = max(dot(n, v), 1e-4);
    var h = l + v;
    let h_length = length(h);
    if h_length > 0.0 {
        h = h / h_length;
    } else {
        h = n;
    }
    let n_dot_h = max(dot(n, h), 0.0);
    let v_dot_h = max(dot(v, h), 0.0);
    let d = blinn_distribution(n_dot_h, blinn_exponent(brdf.roughness));
    let g = shadowing(n_dot_l, n_dot_v, n_dot_h, v_dot_h);
    let f = schlick_fresnel(brdf.specular, v_dot_h);
    let specular = f * (d * g / (4.0 * n_dot_l * n_dot_v));
    return (brdf.diffuse / PI + specular) * n_dot_l;
}

// The environment, +z up: sky over ground, blurred toward its mean as `blur` goes to 1.
struct Environment {
    sky: vec3<f32>,
    ground: vec3<f32>,
}

// Share of the environment reaching diffuse surfaces (`AMBIENT_DIFFUSE`).
const AMBIENT_DIFFUSE: f32 = 0.3;

fn environment(env: Environment, d: vec3<f32>, blur: f32) -> vec3<f32> {
    let sharp = mix(env.ground, env.sky, 0.5 + 0.5 * clamp(d.z, -1.0, 1.0));
    return mix(sharp, 0.5 * (env.ground + env.sky), clamp(blur, 0.0, 1.0));
}

fn environment_light(brdf: Brdf, n: vec3<f32>, v: vec3<f32>, env: Environment) -> vec3<f32> {
    let r = clamp(brdf.roughness, 0.0, 1.0);
    let n_dot_v = clamp(dot(n, v), 0.0, 1.0);
    let mirrored = n * (2.0 * dot(n, v)) - v;
    let grazing = pow(1.0 - n_dot_v, 5.0);
    let fresnel = brdf.specular + (max(vec3<f32>(1.0 - r), brdf.specular) - brdf.specular) * grazing;
    let hemisphere = mix(env.ground, env.sky, 0.5 + 0.5 * clamp(n.z, -1.0, 1.0));
    return brdf.diffuse * hemisphere * AMBIENT_DIFFUSE + fresnel * environment(env, mirrored, r);
}

// Radiance toward the viewer under a key light, a fill light and the environment, clamped.
fn shade(brdf: Brdf, normal: vec3<f32>, v: vec3<f32>, key: Light, fill: Light, env: Environment) -> vec3<f32> {
    var n = normal;
    if dot(n, v) < 0.0 {
        n = -n;
    }
    let radiance = reflect_light(brdf, n, key.direction, v) * key.irradiance
        + reflect_light(brdf, n, fill.direction, v) * fill.irradiance
        + environment_light(brdf, n, v, env);
    return clamp(radiance, vec3<f32>(0.0), vec3<f32>(1.0));
}
