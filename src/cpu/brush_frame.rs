//! Mirror of `wgsl/brush_frame.wgsl` and of the fixed-point sums of `wgsl/shared/fixed.wgsl`,
//! and `frame_from_sums`, which `wgsl/deform.wgsl` computes per invocation (`resolve_frame`).
//! The CPU pipeline takes its brush frames through these functions too, so that every backend
//! gets the same frame bits from the same selection, in whatever order it was appended.

use glam::Vec3;

use crate::abi::{
    FRAME_NORMAL_FROM_SUMS, FRAME_PLANE_FROM_SUMS, FrameParams, FrameSums, SelectedVertex,
};

const FRAME_SUMS: usize = 7;
const FIXED_WORD: f32 = 4294967296.0;
const FIXED_LIMIT: f32 = 2147483520.0;

/// A 96-bit two's-complement fixed-point number with 64 fraction bits: (low, middle, high
/// word).
pub type Fixed = [u32; 3];

fn fixed_negate(x: Fixed) -> Fixed {
    let lo = (!x[0]).wrapping_add(1);
    let mid = (!x[1]).wrapping_add((lo == 0) as u32);
    let hi = (!x[2]).wrapping_add((lo == 0 && mid == 0) as u32);
    [lo, mid, hi]
}

/// `to_fixed` of the shader: `q`'s fraction truncated past 2^-64, zero for NaN and infinities,
/// magnitudes clamped under 2^31.
pub fn to_fixed(q: f32) -> Fixed {
    let a = q.abs();
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(a <= f32::MAX) {
        return [0; 3];
    }
    let clamped = a.min(FIXED_LIMIT);
    // The shader's floors, as truncating casts: the same on values in [0, 2^32), and no call
    // into libm where the CPU has no rounding instruction (x86-64's baseline has none).
    let whole = clamped as u32;
    let upper = (clamped - whole as f32) * FIXED_WORD;
    let upper_whole = upper as u32;
    let magnitude = [
        ((upper - upper_whole as f32) * FIXED_WORD) as u32,
        upper_whole,
        whole,
    ];
    if q < 0.0 {
        fixed_negate(magnitude)
    } else {
        magnitude
    }
}

/// `from_fixed` of the shader: the magnitude in 16-bit pieces, added from the top.
pub fn from_fixed(x: Fixed) -> f32 {
    let negative = x[2] >> 31 == 1;
    let m = if negative { fixed_negate(x) } else { x };
    let v = (m[2] >> 16) as f32 * 65536.0
        + (m[2] & 0xffff) as f32
        + (m[1] >> 16) as f32 * (1.0 / 65536.0)
        + (m[1] & 0xffff) as f32 * (1.0 / FIXED_WORD)
        + (m[0] >> 16) as f32 * (1.0 / (FIXED_WORD * 65536.0))
        + (m[0] & 0xffff) as f32 * (1.0 / (FIXED_WORD * FIXED_WORD));
    if negative { -v } else { v }
}

/// `add_partial` / `add_total` of the shader: word by word, each taking the carry out of the
/// one below.
fn add_fixed(words: &mut [u32], k: usize, x: Fixed) {
    let old_lo = words[3 * k];
    words[3 * k] = old_lo.wrapping_add(x[0]);
    let carry = (old_lo.wrapping_add(x[0]) < old_lo) as u32;
    let mid = x[1].wrapping_add(carry);
    let old_mid = words[3 * k + 1];
    words[3 * k + 1] = old_mid.wrapping_add(mid);
    let carries = (mid < carry) as u32 + (old_mid.wrapping_add(mid) < old_mid) as u32;
    words[3 * k + 2] = words[3 * k + 2].wrapping_add(x[2].wrapping_add(carries));
}

/// What the kernel binds besides its parameters and output.
pub struct FrameInputs<'a> {
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub selected: &'a [SelectedVertex],
    pub selection_count: u32,
}

/// Adds the selection's sums into `sums`. The shader adds each workgroup's partial sums into
/// the totals word by word ([`add_fixed`]); this adds every term into one wide integer and
/// the wide totals into `sums` once: both are sums modulo 2⁹⁶, so the grouping and the width
/// cannot change the bits, and a wide addition is two instructions where the words' carries
/// took a dozen (the frame was a third of the CPU's selection phase on the 1M plane).
pub fn brush_frame(params: &FrameParams, inputs: &FrameInputs<'_>, sums: &mut FrameSums) {
    let count = inputs.selection_count.min(params.capacity);
    let center = Vec3::from_array(params.center);
    let mut totals = [0i128; FRAME_SUMS];
    for entry in &inputs.selected[..count as usize] {
        let (w, v) = (entry.weight, entry.vertex as usize);
        let (n, p) = (inputs.normals[v], inputs.positions[v]);
        let offset = (p - center) * params.inv_radius;
        let terms = [
            w * n.x,
            w * n.y,
            w * n.z,
            w * offset.x,
            w * offset.y,
            w * offset.z,
            w,
        ];
        for (total, q) in totals.iter_mut().zip(terms) {
            *total = total.wrapping_add(widened(to_fixed(q)));
        }
    }
    for (k, total) in totals.into_iter().enumerate() {
        add_fixed(sums, k, narrowed(total));
    }
}

/// A 96-bit fixed-point number as the `i128` of the same value (sign-extended).
fn widened(x: Fixed) -> i128 {
    let bits = (x[2] as u128) << 64 | (x[1] as u128) << 32 | x[0] as u128;
    ((bits << 32) as i128) >> 32
}

/// The low 96 bits of `x`, as [`Fixed`] words.
fn narrowed(x: i128) -> Fixed {
    [x as u32, (x >> 32) as u32, (x >> 64) as u32]
}

/// `resolve_frame` of `wgsl/deform.wgsl`: the normal and plane point of a dab about `center`
/// of `radius`, from the sums as `flags` says, else `normal` and `plane_point` as given.
pub fn frame_from_sums(
    sums: &FrameSums,
    flags: u32,
    (center, radius): (Vec3, f32),
    (normal, plane_point): (Vec3, Vec3),
) -> (Vec3, Vec3) {
    let sum = |k: usize| from_fixed([sums[3 * k], sums[3 * k + 1], sums[3 * k + 2]]);
    let mut resolved = (normal, plane_point);
    if flags & FRAME_NORMAL_FROM_SUMS != 0 {
        let n = Vec3::new(sum(0), sum(1), sum(2));
        let length_squared = n.x * n.x + n.y * n.y + n.z * n.z;
        if (1e-30..=f32::MAX).contains(&length_squared) {
            resolved.0 = n * (1.0 / length_squared.sqrt());
        }
    }
    if flags & FRAME_PLANE_FROM_SUMS != 0 {
        let weight = sum(6);
        resolved.1 = center;
        if weight > 0.0 {
            let offset = Vec3::new(sum(3), sum(4), sum(5));
            resolved.1 = center + offset / weight * radius;
        }
    }
    resolved
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_round_trips_and_sums_in_any_order() {
        for q in [
            0.0f32, 1.0, -1.0, 0.5, -0.25, 1e-9, -3.75e-5, 123.456, -7.0e5,
        ] {
            let back = from_fixed(to_fixed(q));
            assert!(
                (back - q).abs() <= 2.5e-10 + q.abs() * 1.2e-7,
                "{q} -> {back}"
            );
        }
        // Exact from 2^-41 up.
        for q in [3.0e-12f32, -2.0f32.powi(-41), 0.1, -1.0 / 3.0] {
            assert_eq!(from_fixed(to_fixed(q)), q);
        }
        assert_eq!(to_fixed(f32::NAN), [0; 3]);
        assert_eq!(to_fixed(f32::INFINITY), [0; 3]);
        assert_eq!(from_fixed(to_fixed(-1e12)), -FIXED_LIMIT);
        let terms: Vec<f32> = (0..1000)
            .map(|i| ((i * 7919) % 2003) as f32 / 997.0 - 1.0)
            .collect();
        let total = |order: &mut dyn Iterator<Item = &f32>| {
            let mut words = [0u32; 3];
            for &q in order {
                add_fixed(&mut words, 0, to_fixed(q));
            }
            words
        };
        let forward = total(&mut terms.iter());
        assert_eq!(forward, total(&mut terms.iter().rev()));
        let expected: f64 = terms.iter().map(|&q| q as f64).sum();
        let wide = terms
            .iter()
            .fold(0i128, |t, &q| t.wrapping_add(widened(to_fixed(q))));
        assert_eq!(
            narrowed(wide),
            forward,
            "one wide sum, the same bits as the words'"
        );
        assert!((from_fixed(forward) as f64 - expected).abs() < 1e-4);
    }
}
