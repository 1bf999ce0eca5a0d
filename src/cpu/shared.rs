//! Mirrors of the functions in `wgsl/shared/` that the grid module does not already provide
//! (`cell_of` and `hash_cell` are `crate::grid::cell_coordinates` and `crate::grid::hash_cell`).

use crate::abi::WORKGROUP_SIZE;

/// `falloff_weight` of `wgsl/shared/brush.wgsl`: the codes of `crate::abi::falloff_code`, and
/// blend's powers as repeated products in the shader's order (so the mirror may differ from
/// `Falloff::weight`'s `powi` by a few ulps).
pub fn falloff_weight(kind: u32, (blend_n, blend_inner): (u32, f32), t_in: f32) -> f32 {
    // `t_in.is_nan() || t_in >= 1.0`, spelled as the shader does.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(t_in < 1.0) {
        return 0.0;
    }
    let t = t_in.max(0.0);
    match kind {
        0 => {
            if t <= blend_inner {
                return 1.0;
            }
            let t = (t - blend_inner) / (1.0 - blend_inner);
            let mut t_n = 1.0f32;
            for _ in 0..blend_n {
                t_n *= t;
            }
            let base = 1.0 - t_n;
            let mut w = 1.0f32;
            for _ in 0..blend_n {
                w *= base;
            }
            w
        }
        1 => 1.0 - t * t * (3.0 - 2.0 * t),
        2 => (1.0 - t * t).sqrt(),
        _ => 1.0 - t,
    }
}

/// The invocation indices a dispatch over `count` items runs, workgroup by workgroup as the GPU
/// numbers them (`flat_index` in `wgsl/shared/grid.wgsl`), without those past `count` that
/// return at the kernel's first guard.
pub fn invocations(count: u32) -> impl Iterator<Item = u32> {
    (0..count.div_ceil(WORKGROUP_SIZE))
        .flat_map(|workgroup| {
            (0..WORKGROUP_SIZE).map(move |local| workgroup * WORKGROUP_SIZE + local)
        })
        .filter(move |&i| i < count)
}

/// Vertex `v` of a packed x, y, z buffer, as the kernels read positions.
pub fn packed_position(positions: &[f32], v: u32) -> glam::Vec3 {
    let i = 3 * v as usize;
    glam::Vec3::new(positions[i], positions[i + 1], positions[i + 2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::abi::falloff_code;
    use crate::brush::Falloff;

    #[test]
    fn falloff_mirror_matches_the_brush_falloff() {
        // Blend's loop and `powi` multiply in different orders: a few ulps apart at most.
        for falloff in [
            Falloff::blend(3),
            Falloff::blend(8),
            Falloff::Blend { n: 4, inner: 0.4 },
            Falloff::Smooth,
            Falloff::Sphere,
            Falloff::Linear,
        ] {
            let (kind, n, inner) = falloff_code(falloff);
            for k in -10..=1100 {
                let t = k as f32 / 1000.0;
                let (mirror, brush) = (falloff_weight(kind, (n, inner), t), falloff.weight(t));
                assert!(
                    (mirror - brush).abs() <= 1e-6,
                    "{}: t = {t}: {mirror} vs {brush}",
                    falloff.name()
                );
            }
            assert_eq!(falloff_weight(kind, (n, inner), f32::NAN), 0.0);
        }
    }
}
