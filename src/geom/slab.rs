//! The part of a triangle inside axis-aligned slabs (Sutherland–Hodgman clipping against
//! axis planes): what lets the collision grid file a long face only in the cells it passes
//! through, not in every cell of its box.

use glam::Vec3;

/// A convex polygon: a triangle, clipped by at most six axis planes (each adds one corner).
#[derive(Debug, Clone, Copy)]
pub struct Polygon {
    corners: [Vec3; 9],
    len: usize,
}

impl Polygon {
    pub fn triangle(corners: [Vec3; 3]) -> Polygon {
        let mut all = [Vec3::ZERO; 9];
        all[..3].copy_from_slice(&corners);
        Polygon {
            corners: all,
            len: 3,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The part with `lo <= p[axis] <= hi` (for at most six clips in all).
    pub fn within_slab(&self, axis: usize, lo: f32, hi: f32) -> Polygon {
        self.clipped(axis, lo, 1.0).clipped(axis, hi, -1.0)
    }

    /// The part where `side * (p[axis] - at) >= 0`; corners made on the plane lie on it.
    fn clipped(&self, axis: usize, at: f32, side: f32) -> Polygon {
        let mut out = Polygon {
            corners: [Vec3::ZERO; 9],
            len: 0,
        };
        let inside = |p: Vec3| side * (p[axis] - at) >= 0.0;
        for i in 0..self.len {
            let (a, b) = (self.corners[i], self.corners[(i + 1) % self.len]);
            if inside(a) {
                out.push(a);
            }
            if inside(a) != inside(b) {
                let t = (at - a[axis]) / (b[axis] - a[axis]);
                let mut crossing = a + (b - a) * t;
                crossing[axis] = at;
                out.push(crossing);
            }
        }
        out
    }

    fn push(&mut self, p: Vec3) {
        // Six clips of a triangle make at most nine corners; a seventh is a caller's bug.
        self.corners[self.len] = p;
        self.len += 1;
    }

    /// The smallest and largest `p[axis]` over the corners (`None` when empty).
    pub fn range(&self, axis: usize) -> Option<(f32, f32)> {
        let values = self.corners[..self.len].iter().map(|p| p[axis]);
        let lo = values.clone().fold(f32::INFINITY, f32::min);
        let hi = values.fold(f32::NEG_INFINITY, f32::max);
        (self.len > 0).then_some((lo, hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slab_across_a_triangle_keeps_the_band_between_its_planes() {
        let t = Polygon::triangle([
            Vec3::ZERO,
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 4.0, 0.0),
        ]);
        let band = t.within_slab(1, 1.0, 2.0);
        assert_eq!(band.range(1), Some((1.0, 2.0)));
        // At y = 1 the triangle reaches x = 3; at y = 2, x = 2.
        assert_eq!(band.range(0), Some((0.0, 3.0)));
        assert!(t.within_slab(1, 5.0, 6.0).is_empty());
        assert!(t.within_slab(2, 0.5, 1.0).is_empty());
        assert_eq!(t.within_slab(2, -1.0, 1.0).range(0), Some((0.0, 4.0)));
    }
}
