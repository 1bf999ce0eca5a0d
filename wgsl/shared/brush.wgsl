// Brushes on the GPU: falloff curves (as `src/brush/falloff.rs::Falloff::weight`), brush
// kinds, and the selection list `select` writes and `deform` reads. Codes as
// `src/abi/brush.rs::falloff_code` and `brush_code` write them (tests/wgsl.rs checks the
// values).

// One entry of the compacted selection.
struct SelectedVertex {
    vertex: u32,
    weight: f32,
}

const BRUSH_DRAW: u32 = 0u;
const BRUSH_INFLATE: u32 = 1u;
const BRUSH_DEFLATE: u32 = 2u;
const BRUSH_GRAB: u32 = 3u;
const BRUSH_SMOOTH: u32 = 4u;
const BRUSH_FLATTEN: u32 = 5u;
const BRUSH_PINCH: u32 = 6u;
const BRUSH_CREASE: u32 = 7u;
const BRUSH_TWIST: u32 = 8u;
const BRUSH_PAINT: u32 = 9u;
const BRUSH_MASK: u32 = 10u;
const BRUSH_SWEEP: u32 = 11u;
const BRUSH_SWEEP_VOLUME: u32 = 12u;
const BRUSH_TRIM: u32 = 13u;

const FALLOFF_BLEND: u32 = 0u;
const FALLOFF_SMOOTH: u32 = 1u;
const FALLOFF_SPHERE: u32 = 2u;
const FALLOFF_LINEAR: u32 = 3u;

// Weight at normalized distance `t` (1 at the centre, 0 at and past the rim). Blend's integer
// powers are repeated products, never `pow` (exp2/log2 on most GPUs, and wrong for t = 0).
// Blend holds 1 up to `blend_inner` (Freestyle's R_i / R_o) and runs over the rest.
fn falloff_weight(kind: u32, blend_n: u32, blend_inner: f32, t_in: f32) -> f32 {
    // `!(t < 1)` also sends NaN to zero, as the CPU does.
    if !(t_in < 1.0) {
        return 0.0;
    }
    let t = max(t_in, 0.0);
    switch kind {
        case FALLOFF_BLEND: {
            if t <= blend_inner {
                return 1.0;
            }
            let s = (t - blend_inner) / (1.0 - blend_inner);
            var t_n = 1.0;
            for (var k = 0u; k < blend_n; k++) {
                t_n *= s;
            }
            let base = 1.0 - t_n;
            var w = 1.0;
            for (var k = 0u; k < blend_n; k++) {
                w *= base;
            }
            return w;
        }
        case FALLOFF_SMOOTH: {
            return 1.0 - t * t * (3.0 - 2.0 * t);
        }
        case FALLOFF_SPHERE: {
            return sqrt(1.0 - t * t);
        }
        default: {
            return 1.0 - t;
        }
    }
}
