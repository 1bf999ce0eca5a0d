//! The viewport's camera: an orbit about a target point that the user turns, pans and zooms,
//! built on the preview renderer's [`Camera`] so the app and `slayer render` see alike.

use glam::{Vec2, Vec3, Vec4Swizzles};

use super::pick::Ray;
use crate::render::{Camera, CameraSpec};

/// Degrees turned per pixel dragged.
const ORBIT_DEGREES_PER_PIXEL: f32 = 0.35;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitCamera {
    pub target: Vec3,
    /// Degrees, as [`CameraSpec`]'s.
    pub azimuth: f32,
    pub elevation: f32,
    /// From the eye to the target, world units.
    pub distance: f32,
    /// Diameter of the scene's box: sets the depth range.
    pub extent: f32,
    /// Box of the scene, kept to re-frame it.
    bounds: (Vec3, Vec3),
}

impl OrbitCamera {
    /// The camera `slayer render` would use for `bounds`, at `aspect` = width / height.
    pub fn framing(bounds: Option<(Vec3, Vec3)>, aspect: f32) -> OrbitCamera {
        let bounds = bounds.unwrap_or((Vec3::ZERO, Vec3::ONE));
        let spec = CameraSpec::default();
        let fitted = Camera::fit(&spec, Some(bounds), aspect);
        OrbitCamera {
            target: fitted.target,
            azimuth: spec.azimuth,
            elevation: spec.elevation,
            distance: (fitted.eye - fitted.target).length(),
            extent: (bounds.1 - bounds.0).length().max(1e-3),
            bounds,
        }
    }

    /// Frames the box again, keeping the direction of view.
    pub fn frame_all(&mut self, aspect: f32) {
        let spec = CameraSpec {
            azimuth: self.azimuth,
            elevation: self.elevation,
            distance: 1.0,
        };
        let fitted = Camera::fit(&spec, Some(self.bounds), aspect);
        self.target = fitted.target;
        self.distance = (fitted.eye - fitted.target).length();
    }

    /// Keeps the view but lets the depth range cover a scene that grew or moved.
    pub fn set_bounds(&mut self, bounds: Option<(Vec3, Vec3)>) {
        if let Some(bounds) = bounds {
            self.bounds = bounds;
            self.extent = (bounds.1 - bounds.0).length().max(1e-3);
        }
    }

    pub fn view(&self, aspect: f32) -> Camera {
        // The far plane must reach the box's far side from wherever the target was panned.
        let reach =
            self.extent + 2.0 * (0.5 * (self.bounds.0 + self.bounds.1) - self.target).length();
        Camera::orbit(
            self.target,
            (self.azimuth, self.elevation),
            self.distance,
            reach,
            aspect,
        )
    }

    /// Turns the view by a drag of `delta` pixels.
    pub fn orbit(&mut self, delta: Vec2) {
        self.azimuth = (self.azimuth - delta.x * ORBIT_DEGREES_PER_PIXEL).rem_euclid(360.0);
        self.elevation = (self.elevation + delta.y * ORBIT_DEGREES_PER_PIXEL).clamp(-89.0, 89.0);
    }

    /// Moves the target with a drag of `delta` pixels in a viewport `height` pixels tall, so the
    /// point under the cursor at the target's depth follows the cursor.
    pub fn pan(&mut self, delta: Vec2, height: f32, aspect: f32) {
        let camera = self.view(aspect);
        self.target +=
            (-delta.x * camera.right + delta.y * camera.up) * self.world_per_pixel(height);
    }

    /// World units a pixel spans at the target's depth, in a viewport `height` pixels tall.
    pub fn world_per_pixel(&self, height: f32) -> f32 {
        2.0 * self.distance * (0.5 * crate::render::FIELD_OF_VIEW_DEGREES.to_radians()).tan()
            / height.max(1.0)
    }

    /// Moves toward the target (`steps` > 0) or away, 10 % a step.
    pub fn zoom(&mut self, steps: f32) {
        let smallest = 1e-4 * self.extent;
        self.distance = (self.distance * 0.9f32.powf(steps)).clamp(smallest, 100.0 * self.extent);
    }

    /// The ray through `pixel` (from the viewport's top-left) of a viewport of `size` pixels.
    pub fn ray(&self, pixel: Vec2, size: Vec2) -> Ray {
        let camera = self.view(size.x / size.y.max(1.0));
        let ndc = Vec2::new(2.0 * pixel.x / size.x - 1.0, 1.0 - 2.0 * pixel.y / size.y);
        let inverse = camera.view_proj.inverse();
        let unproject = |depth: f32| {
            let p = inverse * ndc.extend(depth).extend(1.0);
            p.xyz() / p.w
        };
        let (near, far) = (unproject(0.0), unproject(1.0));
        Ray {
            origin: near,
            direction: (far - near).normalize_or(-camera.toward),
        }
    }

    /// Where `point` lands in a viewport of `size` pixels, if it is in front of the eye.
    pub fn project(&self, point: Vec3, size: Vec2) -> Option<Vec2> {
        let camera = self.view(size.x / size.y.max(1.0));
        let clip = camera.view_proj * point.extend(1.0);
        (clip.w > 1e-9).then(|| {
            let ndc = clip.xy() / clip.w;
            Vec2::new((ndc.x + 1.0) * 0.5 * size.x, (1.0 - ndc.y) * 0.5 * size.y)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pixel_ray_passes_through_the_point_projected_there() {
        let mut camera = OrbitCamera::framing(Some((Vec3::ZERO, Vec3::new(1.0, 1.0, 0.2))), 1.5);
        camera.orbit(Vec2::new(40.0, -25.0));
        camera.pan(Vec2::new(12.0, 7.0), 600.0, 1.5);
        camera.zoom(3.0);
        let size = Vec2::new(900.0, 600.0);
        for point in [Vec3::new(0.3, 0.7, 0.1), Vec3::new(0.9, 0.1, 0.0)] {
            let pixel = camera.project(point, size).unwrap();
            let ray = camera.ray(pixel, size);
            let along = (point - ray.origin).dot(ray.direction);
            let miss = (ray.at(along) - point).length();
            assert!(miss < 1e-4, "{point}: the ray misses it by {miss}");
        }
    }

    #[test]
    fn framing_matches_the_renderers_camera() {
        let bounds = (Vec3::new(-1.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 0.5));
        let camera = OrbitCamera::framing(Some(bounds), 4.0 / 3.0);
        let rendered = Camera::fit(&CameraSpec::default(), Some(bounds), 4.0 / 3.0);
        assert!((camera.view(4.0 / 3.0).eye - rendered.eye).length() < 1e-5);
    }
}
