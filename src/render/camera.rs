//! The preview camera: an orbit around the mesh's bounding box, `+z` up (the generated scenes are
//! sheets on the unit square in the xy plane, heights along z), framed so the whole box fits.

use glam::{Mat4, Vec3};

/// Vertical field of view of the preview, degrees.
pub const FIELD_OF_VIEW_DEGREES: f32 = 30.0;
/// Share of the image left as margin around the fitted box.
const MARGIN: f32 = 1.06;

/// Where the camera sits, as a user gives it: `azimuth,elevation[,distance]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSpec {
    /// Degrees around `+z`, counter-clockwise seen from above; 0 looks from `−y` toward `+y`.
    pub azimuth: f32,
    /// Degrees above the xy plane; 90 looks straight down.
    pub elevation: f32,
    /// Multiple of the distance at which the whole mesh just fits (below 1 zooms in).
    pub distance: f32,
}

impl Default for CameraSpec {
    /// A three-quarter view from above.
    fn default() -> Self {
        CameraSpec {
            azimuth: -30.0,
            elevation: 50.0,
            distance: 1.0,
        }
    }
}

impl std::str::FromStr for CameraSpec {
    type Err = String;

    /// `azimuth,elevation` or `azimuth,elevation,distance` (degrees, degrees, multiple of the
    /// fitted distance).
    fn from_str(text: &str) -> Result<CameraSpec, String> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        if !(2..=3).contains(&parts.len()) {
            return Err(format!(
                "`{text}` is not `azimuth,elevation[,distance]` (e.g. `-30,50` or `0,90,0.5`)"
            ));
        }
        let number = |s: &str, what: &str| -> Result<f32, String> {
            s.parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("camera {what} `{s}` is not a number"))
        };
        let azimuth = number(parts[0], "azimuth")?;
        let elevation = number(parts[1], "elevation")?;
        if !(-90.0..=90.0).contains(&elevation) {
            return Err(format!(
                "camera elevation {elevation} is outside -90..=90 degrees"
            ));
        }
        let distance = match parts.get(2) {
            Some(s) => number(s, "distance")?,
            None => 1.0,
        };
        if !(0.01..=100.0).contains(&distance) {
            return Err(format!(
                "camera distance {distance} is outside 0.01..=100 (a multiple of the fitted distance)"
            ));
        }
        Ok(CameraSpec {
            azimuth,
            elevation,
            distance,
        })
    }
}

/// A placed camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    /// Unit vectors of the image plane and toward the camera.
    pub right: Vec3,
    pub up: Vec3,
    pub toward: Vec3,
    pub view_proj: Mat4,
}

impl Camera {
    /// Frames the box `bounds` (or the unit cube when there is nothing to frame) for an image of
    /// `aspect` = width / height.
    pub fn fit(spec: &CameraSpec, bounds: Option<(Vec3, Vec3)>, aspect: f32) -> Camera {
        let (lo, hi) = bounds.unwrap_or((Vec3::ZERO, Vec3::ONE));
        let target = 0.5 * (lo + hi);
        // A box with no extent (one point) still gets a camera at a sane distance.
        let extent = (hi - lo).length().max(1e-3);
        let (toward, up) = orbit_axes(spec.azimuth, spec.elevation);
        let right = up.cross(toward);
        let tan_y = (0.5 * FIELD_OF_VIEW_DEGREES.to_radians()).tan();
        let tan_x = tan_y * aspect.max(1e-3);
        // Smallest distance at which every corner of the box is inside the frustum.
        let mut fitted = 0.0f32;
        for k in 0..8 {
            let corner = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ) - target;
            let depth = corner.dot(toward);
            let need_x = depth + MARGIN * corner.dot(right).abs() / tan_x;
            let need_y = depth + MARGIN * corner.dot(up).abs() / tan_y;
            fitted = fitted.max(need_x).max(need_y);
        }
        let distance = fitted.max(0.5 * extent) * spec.distance;
        Camera::orbit(
            target,
            (spec.azimuth, spec.elevation),
            distance,
            extent,
            aspect,
        )
    }

    /// The camera `distance` from `target`, at `azimuth` and `elevation` (degrees, as in
    /// [`CameraSpec`]), its depth range wide enough for a scene of diameter `extent` around
    /// the target.
    pub fn orbit(
        target: Vec3,
        (azimuth, elevation): (f32, f32),
        distance: f32,
        extent: f32,
        aspect: f32,
    ) -> Camera {
        let (toward, up) = orbit_axes(azimuth, elevation);
        let right = up.cross(toward);
        let eye = target + toward * distance;
        let near = (distance - extent).max(distance * 1e-3);
        let far = distance + extent;
        let view = glam::camera::rh::view::look_at_mat4(eye, target, up);
        // wgpu's clip space is Direct3D's: depth in [0, 1], y up.
        let proj = glam::camera::rh::proj::directx::perspective(
            FIELD_OF_VIEW_DEGREES.to_radians(),
            aspect.max(1e-3),
            near,
            far,
        );
        Camera {
            eye,
            target,
            right,
            up,
            toward,
            view_proj: proj * view,
        }
    }
}

/// The direction from the target to the eye, and the up vector, at `azimuth` and `elevation`
/// in degrees.
fn orbit_axes(azimuth: f32, elevation: f32) -> (Vec3, Vec3) {
    let (azimuth, elevation) = (azimuth.to_radians(), elevation.to_radians());
    let toward = Vec3::new(
        elevation.cos() * azimuth.sin(),
        elevation.cos() * -azimuth.cos(),
        elevation.sin(),
    );
    // The up vector in the plane of `toward` and z, continuous through a straight-down view.
    let up = Vec3::new(
        -elevation.sin() * azimuth.sin(),
        elevation.sin() * azimuth.cos(),
        elevation.cos(),
    );
    (toward, up)
}
