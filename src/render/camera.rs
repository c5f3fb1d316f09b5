//! The pinhole camera and automatic framing.

use glam::Vec3A;

use crate::geom::{Aabb, Ray};

/// A pinhole camera. Y is up in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3A,
    /// Unit vector to the right of the image.
    pub right: Vec3A,
    /// Unit vector to the top of the image.
    pub up: Vec3A,
    /// Unit viewing direction.
    pub forward: Vec3A,
    /// `tan(vertical field of view / 2)`.
    pub tan_half_fov: f32,
    /// Image width over height.
    pub aspect: f32,
}

impl Camera {
    /// A camera at `eye` looking at `target`, with a vertical field of view
    /// of `fov_deg` degrees, for an image of `width × height` pixels.
    /// Looking straight up or down picks another up hint.
    pub fn look_at(eye: Vec3A, target: Vec3A, fov_deg: f32, width: u32, height: u32) -> Self {
        let forward = (target - eye).try_normalize().unwrap_or(Vec3A::NEG_Z);
        let hint = if forward.cross(Vec3A::Y).length_squared() < 1e-8 {
            Vec3A::Z
        } else {
            Vec3A::Y
        };
        let right = forward.cross(hint).normalize();
        let up = right.cross(forward);
        Self {
            eye,
            right,
            up,
            forward,
            tan_half_fov: (fov_deg.to_radians() * 0.5).tan(),
            aspect: width.max(1) as f32 / height.max(1) as f32,
        }
    }

    /// A camera that frames `bounds`: it looks at the box centre from the
    /// direction given by `azimuth_deg` (around the vertical axis, 0 = from
    /// +z) and `elevation_deg` (above the horizon), from the nearest
    /// distance at which all eight corners of the box are in the image with
    /// a small margin.
    pub fn frame(
        bounds: &Aabb,
        azimuth_deg: f32,
        elevation_deg: f32,
        fov_deg: f32,
        width: u32,
        height: u32,
    ) -> Self {
        let bounds = if bounds.is_empty() {
            Aabb::from_arrays([-1.0; 3], [1.0; 3])
        } else {
            *bounds
        };
        let center = bounds.center();
        let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
        let back = Vec3A::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
        let radius = bounds.half_extents().length().max(1e-6);
        // The probe only fixes the orientation; it stands a radius away, not
        // one unit: far from the origin `center + back` rounds to `center`
        // in f32 and the view direction would be NaN (an empty image).
        let probe = Camera::look_at(center + back * radius, center, fov_deg, width, height);
        let ty = probe.tan_half_fov / 1.12;
        let tx = ty * probe.aspect;
        let mut dist: f32 = 0.0;
        for c in bounds.corners() {
            let r = c - center;
            let (x, y, z) = (r.dot(probe.right), r.dot(probe.up), r.dot(probe.forward));
            // The corner is at depth `dist + z` in front of the eye.
            dist = dist
                .max(x.abs() / tx - z)
                .max(y.abs() / ty - z)
                .max(z + 1e-3 * radius);
        }
        let eye = center + back * dist;
        Camera { eye, ..probe }
    }

    /// The primary ray through the centre of pixel `(x, y)` (row 0 at the
    /// top) of a `width × height` image, with a unit direction.
    #[inline]
    pub fn primary_ray(&self, x: u32, y: u32, width: u32, height: u32) -> Ray {
        let sx = (2.0 * (x as f32 + 0.5) / width as f32 - 1.0) * self.tan_half_fov * self.aspect;
        let sy = (1.0 - 2.0 * (y as f32 + 0.5) / height as f32) * self.tan_half_fov;
        let dir = (self.forward + self.right * sx + self.up * sy).normalize();
        Ray::new(self.eye, dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framed_corners_project_inside_the_image() {
        let b = Aabb::from_arrays([-0.4, 0.0, -0.3], [0.4, 2.1, 0.3]);
        for (w, h) in [(64, 48), (48, 64)] {
            let cam = Camera::frame(&b, 30.0, 15.0, 35.0, w, h);
            for c in b.corners() {
                let r = c - cam.eye;
                let z = r.dot(cam.forward);
                assert!(z > 0.0);
                let x = r.dot(cam.right) / z / (cam.tan_half_fov * cam.aspect);
                let y = r.dot(cam.up) / z / cam.tan_half_fov;
                assert!(x.abs() <= 1.0 && y.abs() <= 1.0, "{x} {y}");
            }
            // Tight: some corner is near the border.
            let m = b
                .corners()
                .iter()
                .map(|c| {
                    let r = *c - cam.eye;
                    let z = r.dot(cam.forward);
                    (r.dot(cam.right) / z / (cam.tan_half_fov * cam.aspect))
                        .abs()
                        .max((r.dot(cam.up) / z / cam.tan_half_fov).abs())
                })
                .fold(0.0f32, f32::max);
            assert!(m > 0.85, "{m}");
        }
    }
}
