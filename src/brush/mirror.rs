//! Symmetric sculpting: every sample is brushed together with its image across a plane
//! (`"symmetry"` in a stroke file, `slayer sculpt --symmetry x`).

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::mesh::Mesh;

/// A mirror plane through `point` with unit `normal`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mirror {
    pub point: Vec3,
    pub normal: Vec3,
}

impl Mirror {
    /// The plane through `point` across `normal`; `None` for a zero or non-finite normal or
    /// point.
    pub fn new(point: Vec3, normal: Vec3) -> Option<Mirror> {
        let normal = normal.try_normalize()?;
        point.is_finite().then_some(Mirror { point, normal })
    }

    /// The plane across axis `axis` (0, 1, 2: x, y, z) through the centre of `mesh`'s bounds.
    /// A mesh mirrored about a coordinate plane through the origin has its centre exactly there,
    /// so its images are exact (a negated coordinate).
    pub fn axis_through_centre(axis: usize, mesh: &Mesh) -> Mirror {
        let centre = mesh.bounds().map_or(Vec3::ZERO, |(lo, hi)| (lo + hi) * 0.5);
        let mut normal = Vec3::ZERO;
        normal[axis] = 1.0;
        Mirror {
            point: centre,
            normal,
        }
    }

    /// The image of a point.
    pub fn point_image(&self, p: Vec3) -> Vec3 {
        p - 2.0 * (p - self.point).dot(self.normal) * self.normal
    }

    /// The image of a direction (a motion, a normal).
    pub fn direction_image(&self, d: Vec3) -> Vec3 {
        d - 2.0 * d.dot(self.normal) * self.normal
    }
}

/// The `symmetry` of a stroke as written in the file: `"x"`, `"y"` or `"z"` (the plane across
/// that axis through the mesh's centre), or a plane `{"point": [..], "normal": [..]}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum SymmetrySpec {
    Axis(String),
    Plane { point: [f32; 3], normal: [f32; 3] },
}

impl SymmetrySpec {
    /// The mirror on `mesh`, or what is wrong with the spec.
    pub fn resolve(&self, mesh: &Mesh) -> Result<Mirror, String> {
        match self {
            SymmetrySpec::Axis(axis) => match axis.as_str() {
                "x" => Ok(Mirror::axis_through_centre(0, mesh)),
                "y" => Ok(Mirror::axis_through_centre(1, mesh)),
                "z" => Ok(Mirror::axis_through_centre(2, mesh)),
                other => Err(format!(
                    "{:?} is not an axis (x, y, z) or a plane {{\"point\": [..], \"normal\": [..]}}",
                    crate::files::escape(other)
                )),
            },
            SymmetrySpec::Plane { point, normal } => {
                Mirror::new(Vec3::from(*point), Vec3::from(*normal)).ok_or_else(|| {
                    format!("the plane through {point:?} across {normal:?} is not a plane")
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn images_across_a_coordinate_plane_through_the_origin_are_exact() {
        let mirror = Mirror::new(Vec3::ZERO, Vec3::X).unwrap();
        let p = Vec3::new(0.123_456_7, -3.3, 1e-7);
        assert_eq!(mirror.point_image(p), Vec3::new(-p.x, p.y, p.z));
        assert_eq!(mirror.direction_image(Vec3::ONE), Vec3::new(-1.0, 1.0, 1.0));
        let tilted = Mirror::new(Vec3::ONE, Vec3::new(1.0, 1.0, 0.0)).unwrap();
        let back = tilted.point_image(tilted.point_image(p));
        assert!(back.distance(p) < 1e-5);
        assert!(Mirror::new(Vec3::ZERO, Vec3::ZERO).is_none());
    }
}
