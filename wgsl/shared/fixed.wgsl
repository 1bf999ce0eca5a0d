// Sums that do not depend on the order they are taken in: 96-bit two's-complement fixed point
// with 64 fraction bits, held as vec3<u32>(low, middle, high word) (WGSL has no 64-bit integers
// and no float atomics). Integer addition is associative, so a sum over atomic appends comes out
// the same bits on every run and every backend; 64 fraction bits hold every f32 from 2^-41 up
// exactly, so a sum of a few small terms (a brush grazing a surface with its rim) keeps its
// precision. Mirror: src/cpu/brush_frame.rs.

const FIXED_WORD: f32 = 4294967296.0;
// The largest f32 below 2^31: magnitudes are clamped under it.
const FIXED_LIMIT: f32 = 2147483520.0;

fn fixed_negate(x: vec3<u32>) -> vec3<u32> {
    let lo = ~x.x + 1u;
    let mid = ~x.y + select(0u, 1u, lo == 0u);
    let hi = ~x.z + select(0u, 1u, lo == 0u && mid == 0u);
    return vec3<u32>(lo, mid, hi);
}

// `q` in fixed point, its fraction truncated past 2^-64; zero for NaN and infinities (they
// fail the comparison), magnitudes clamped under 2^31. Every step is exact but the last
// truncation: `a - floor(a)` keeps `a`'s fraction bits, and 2^32 is a power of two.
fn to_fixed(q: f32) -> vec3<u32> {
    let a = abs(q);
    if !(a <= 3.40282347e38) {
        return vec3<u32>(0u);
    }
    let clamped = min(a, FIXED_LIMIT);
    let whole = floor(clamped);
    let upper = (clamped - whole) * FIXED_WORD;
    let upper_whole = floor(upper);
    let magnitude = vec3<u32>(u32((upper - upper_whole) * FIXED_WORD), u32(upper_whole), u32(whole));
    if q < 0.0 {
        return fixed_negate(magnitude);
    }
    return magnitude;
}

// `x` as an f32: its magnitude in 16-bit pieces (each converts exactly), added from the most
// significant down; the same additions on every backend.
fn from_fixed(x: vec3<u32>) -> f32 {
    let negative = (x.z >> 31u) == 1u;
    var m = x;
    if negative {
        m = fixed_negate(x);
    }
    let v = f32(m.z >> 16u) * 65536.0 + f32(m.z & 0xffffu) + f32(m.y >> 16u) * (1.0 / 65536.0)
        + f32(m.y & 0xffffu) * (1.0 / FIXED_WORD) + f32(m.x >> 16u) * (1.0 / (FIXED_WORD * 65536.0))
        + f32(m.x & 0xffffu) * (1.0 / (FIXED_WORD * FIXED_WORD));
    return select(v, -v, negative);
}
