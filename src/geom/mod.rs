//! Geometric primitives shared by the grid, collision and the checks: closest point on a triangle
//! (Ericson, Real-Time Collision Detection §5.1.5), ray–triangle (Möller–Trumbore) and an exact
//! triangle–triangle intersection test on Shewchuk's adaptive predicates.

mod closest_point;
mod fan;
mod order_free;
mod ray;
mod separation;
mod slab;
mod tri_tri;

pub use closest_point::{
    closest_point_on_triangle, point_triangle_distance, point_triangle_distance_squared,
};
pub use fan::fan_projects_one_to_one;
pub use order_free::{corner_cross, fan_normal, order_free_sum};
pub use ray::{Ray, ray_triangle};
pub use separation::surely_disjoint;
pub use slab::Polygon;
pub use tri_tri::{neighbours_overlap, triangles_intersect};

use glam::Vec3;

/// The point of the segment `ab` closest to `p`, and its parameter from `a` (0) to `b` (1); `a`
/// for a degenerate segment.
pub fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> (f32, Vec3) {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
    (t, a + ab * t)
}

/// The farthest any point moves from `from[i]` to `to[i]` (0 for none): the drift and step
/// bounds the broad phases grow their reach by.
pub fn largest_move(from: &[Vec3], to: &[Vec3]) -> f32 {
    debug_assert_eq!(from.len(), to.len(), "one destination per point");
    from.iter()
        .zip(to)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0f32, f32::max)
}

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Aabb::EMPTY
    }
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn of_points(points: &[Vec3]) -> Aabb {
        points.iter().fold(Aabb::EMPTY, |b, &p| b.including(p))
    }

    pub fn including(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn including_box(self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn expanded(self, by: f32) -> Aabb {
        Aabb {
            min: self.min - Vec3::splat(by),
            max: self.max + Vec3::splat(by),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// True when some point of the box is closer than `distance` to `p`.
    #[inline]
    pub fn within(&self, p: Vec3, distance: f32) -> bool {
        self.distance_squared_to(p) < distance * distance
    }

    /// The squared distance from `p` to the nearest point of the box (0 inside).
    #[inline]
    pub fn distance_squared_to(&self, p: Vec3) -> f32 {
        (self.min - p)
            .max(p - self.max)
            .max(Vec3::ZERO)
            .length_squared()
    }

    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }
}
