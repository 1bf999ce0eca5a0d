//! Sums over a vertex's fan or ring that do not depend on the order of its faces, so that a
//! mirrored mesh gets mirrored normals and smoothing to the bit.
//!
//! A reflection reverses every fan: summing in fan order rounds differently on the two sides,
//! and a later stroke's selection boundary can grow those ulps into whole-vertex differences.
//! Here the terms are seen from the vertex itself (a reflection maps each to the reflected one
//! exactly) and summed in integers, which do not care about order. The integers are 32-bit, at
//! the fan's own scale: `wgsl/shared/fixed.wgsl`'s 96-bit sums (the brush frame's, over the
//! whole selection) would cost three words and carries per term. Mirror:
//! `wgsl/shared/order_free.wgsl`.

use glam::{IVec3, Vec3};

/// Bits kept of each term's components, relative to the largest component of all terms: far
/// below f32 rounding in a normal's direction or a centroid's place, and 512 terms sum within
/// `i32`.
const TERM_BITS: u32 = 22;

/// The cross product of `face` at its corner `v`: `(p − v) × (q − v)`, where `p` and `q`
/// follow `v` in the face's winding (`position` gives a vertex's position). Twice the face's
/// area along its normal, the same whichever corner the face lists first.
pub fn corner_cross(face: [u32; 3], v: u32, position: impl Fn(u32) -> Vec3) -> Vec3 {
    let [a, b, c] = face;
    let [p, q] = match v {
        _ if v == a => [b, c],
        _ if v == b => [c, a],
        _ => [a, b],
    };
    let at = position(v);
    (position(p) - at).cross(position(q) - at)
}

/// The unit normal of a fan from its faces' [`corner_cross`]es (`fan` yields them, and is
/// called twice): the direction of their [`integer_sum`]. `+Z` where the sum vanishes, a term
/// is not finite, or all are below `f32::MIN_POSITIVE` (a fan of degenerate faces).
pub fn fan_normal<I: Iterator<Item = Vec3>>(fan: impl Fn() -> I) -> Vec3 {
    let IntegerSum::Sum(sum, _) = integer_sum(fan) else {
        return Vec3::Z;
    };
    let sum = sum.as_vec3();
    // glam's try_normalize: the reciprocal of the length must be finite and positive.
    let rcp = 1.0 / sum.dot(sum).sqrt();
    if rcp.is_finite() && rcp > 0.0 {
        sum * rcp
    } else {
        Vec3::Z
    }
}

/// The sum of the `terms` (yielded by `terms`, called twice) whatever their order, each
/// rounded toward zero to [`TERM_BITS`] below the largest component's power of two: zero when
/// they are all below `f32::MIN_POSITIVE`, `None` when one is not finite.
pub fn order_free_sum<I: Iterator<Item = Vec3>>(terms: impl Fn() -> I) -> Option<Vec3> {
    match integer_sum(terms) {
        IntegerSum::NotFinite => None,
        IntegerSum::Vanishing => Some(Vec3::ZERO),
        IntegerSum::Sum(sum, exponent) => Some(scaled(sum.as_vec3(), -exponent)),
    }
}

/// What [`integer_sum`] found.
enum IntegerSum {
    /// A term is not finite.
    NotFinite,
    /// Every component of every term is below `f32::MIN_POSITIVE` (or there are no terms).
    Vanishing,
    /// The sum of the terms, each scaled by `2^exponent` and truncated, and that exponent.
    Sum(IVec3, i32),
}

/// The terms' sum in integers. Integer addition is associative, so the order of the terms does
/// not matter, and a reflection (negated components) reflects the sum exactly.
fn integer_sum<I: Iterator<Item = Vec3>>(terms: impl Fn() -> I) -> IntegerSum {
    // A fan's terms are kept from the first pass, so the second reads them instead of
    // computing them again; only a fan longer than this computes them twice.
    let mut kept = [Vec3::ZERO; 16];
    let mut largest = 0.0f32;
    let mut count = 0u32;
    for term in terms() {
        if !term.is_finite() {
            return IntegerSum::NotFinite;
        }
        if let Some(slot) = kept.get_mut(count as usize) {
            *slot = term;
        }
        largest = largest.max(term.abs().max_element());
        count += 1;
    }
    if largest < f32::MIN_POSITIVE {
        return IntegerSum::Vanishing;
    }
    // `largest < 2^above`; every term is scaled to below 2^bits, so `count` of them sum within
    // 2^31.
    let above = (largest.to_bits() >> 23) as i32 - 126;
    let bits = TERM_BITS.min(31 - ceil_log2(count)) as i32;
    let exponent = bits - above;
    // `as` casts truncate toward zero, and every scaled term is finite and within i32.
    let mut sum = IVec3::ZERO;
    if count as usize <= kept.len() {
        for &term in &kept[..count as usize] {
            sum += scaled(term, exponent).as_ivec3();
        }
    } else {
        for term in terms() {
            sum += scaled(term, exponent).as_ivec3();
        }
    }
    IntegerSum::Sum(sum, exponent)
}

/// `x · 2^exponent`, by two powers of two (the exponent may pass f32's range); exact but where
/// the result is subnormal.
fn scaled(x: Vec3, exponent: i32) -> Vec3 {
    let first = exponent.div_euclid(2);
    x * power_of_two(first) * power_of_two(exponent - first)
}

/// The smallest `k` with `2^k >= count` (`count >= 1`).
fn ceil_log2(count: u32) -> u32 {
    32 - (count - 1).leading_zeros()
}

/// `2^exponent` for −126 ≤ `exponent` ≤ 127, built from its bits (exact on the CPU and WGSL).
fn power_of_two(exponent: i32) -> f32 {
    f32::from_bits(((exponent + 127) as u32) << 23)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn normal_of(crosses: &[Vec3]) -> Vec3 {
        fan_normal(|| crosses.iter().copied())
    }

    #[test]
    fn order_does_not_matter_and_a_reflection_reflects() {
        let crosses = [
            Vec3::new(0.1, 0.7, 0.3),
            Vec3::new(-0.33, 0.21, 0.9),
            Vec3::new(1e-3, -0.4, 0.77),
            Vec3::new(0.123_456_7, 0.2, 0.0),
        ];
        let n = normal_of(&crosses);
        let mut reversed = crosses;
        reversed.reverse();
        assert_eq!(normal_of(&reversed), n);
        let mirrored: Vec<Vec3> = reversed
            .iter()
            .map(|c| c * Vec3::new(-1.0, 1.0, 1.0))
            .collect();
        assert_eq!(normal_of(&mirrored), n * Vec3::new(-1.0, 1.0, 1.0));
        let exact = crosses.iter().sum::<Vec3>().normalize();
        assert!(n.distance(exact) < 1e-6, "{n} against {exact}");
    }

    #[test]
    fn degenerate_and_huge_fans() {
        assert_eq!(normal_of(&[]), Vec3::Z);
        assert_eq!(normal_of(&[Vec3::ZERO, Vec3::ZERO]), Vec3::Z);
        assert_eq!(normal_of(&[Vec3::new(f32::NAN, 0.0, 1.0)]), Vec3::Z);
        assert_eq!(normal_of(&[Vec3::splat(1e-39)]), Vec3::Z);
        let big = normal_of(&[Vec3::new(3e38, 0.0, 0.0), Vec3::new(3e38, 0.0, 0.0)]);
        assert_eq!(big, Vec3::X);
        let tiny = normal_of(&[Vec3::new(0.0, -2e-37, 0.0)]);
        assert_eq!(tiny, -Vec3::Y);
        // 4,000 faces: fewer bits each, still no overflow.
        let many = vec![Vec3::new(0.0, 0.0, 1.0); 4000];
        assert_eq!(normal_of(&many), Vec3::Z);
    }

    #[test]
    fn sums_are_close_and_order_free() {
        let terms = [
            Vec3::new(0.25, -1.5, 3.0),
            Vec3::new(-0.125, 2.0, 1e-3),
            Vec3::new(7.0, 0.5, -2.0),
        ];
        let sum = |t: &[Vec3]| order_free_sum(|| t.iter().copied());
        let exact: Vec3 = terms.iter().sum();
        let got = sum(&terms).unwrap();
        assert!(got.distance(exact) < 2e-5, "{got} against {exact}");
        let reversed: Vec<Vec3> = terms
            .iter()
            .rev()
            .map(|t| t * Vec3::new(1.0, -1.0, 1.0))
            .collect();
        assert_eq!(sum(&reversed).unwrap(), got * Vec3::new(1.0, -1.0, 1.0));
        assert_eq!(sum(&[Vec3::ZERO]), Some(Vec3::ZERO));
        assert_eq!(sum(&[]), Some(Vec3::ZERO));
        assert_eq!(sum(&[Vec3::new(1.0, f32::INFINITY, 0.0)]), None);
    }
}
