// Sums over a vertex's fan or ring that do not depend on the order of its faces, so that a
// mirrored mesh gets mirrored normals and smoothing to the bit (a reflection reverses every
// fan). Each term is seen from the vertex (a reflection maps it exactly), scaled by a power of
// two that puts the largest component of all terms just under 2^bits, truncated, and summed
// in i32: integer addition is associative. The caller takes two passes over its terms: the
// first finds the largest component (`order_free_exponent`), the second sums
// `order_free_term`s. Mirror: src/geom/order_free.rs.

// Largest finite f32: WGSL has no isfinite.
const ORDER_FREE_MAX_F32: f32 = 3.40282347e38;
// Smallest normal f32: below it every term vanishes.
const ORDER_FREE_MIN_F32: f32 = 1.17549435e-38;
// Bits kept of each term below the largest component's power of two (fewer for over 512
// terms, so that their sum fits in i32).
const ORDER_FREE_BITS: u32 = 22u;

// Whether every component of `term` is finite.
fn order_free_finite(term: vec3<f32>) -> bool {
    return all(abs(term) <= vec3<f32>(ORDER_FREE_MAX_F32));
}

// The largest absolute component of `term`.
fn order_free_largest(term: vec3<f32>) -> f32 {
    let a = abs(term);
    return max(a.x, max(a.y, a.z));
}

// The power of two `count` terms whose largest component is `largest` (a normal f32) are
// scaled by: each below 2^bits, their sum within 2^31.
fn order_free_exponent(largest: f32, count: u32) -> i32 {
    let above = i32(bitcast<u32>(largest) >> 23u) - 126;
    let ceil_log2 = 32u - countLeadingZeros(count - 1u);
    return i32(min(ORDER_FREE_BITS, 31u - ceil_log2)) - above;
}

// 2^e for -126 <= e <= 127, from its bits.
fn order_free_power(e: i32) -> f32 {
    return bitcast<f32>(u32(e + 127) << 23u);
}

// x · 2^exponent by two powers of two (the exponent may pass f32's range).
fn order_free_scaled(x: vec3<f32>, exponent: i32) -> vec3<f32> {
    let first = exponent >> 1u;
    return x * order_free_power(first) * order_free_power(exponent - first);
}

fn order_free_term(term: vec3<f32>, exponent: i32) -> vec3<i32> {
    return vec3<i32>(trunc(order_free_scaled(term, exponent)));
}

// The sum of the terms in their own units.
fn order_free_value(sum: vec3<i32>, exponent: i32) -> vec3<f32> {
    return order_free_scaled(vec3<f32>(sum), -exponent);
}
