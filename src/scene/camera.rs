//! The pinhole camera and its convention.
//!
//! forward = look_at − position; right = forward × up (right-handed world); the image's
//! row 0 is at the top; the primary ray of pixel (x, y) passes through the pixel centre
//! (x + 0.5, y + 0.5) unless jittered. `fov_y` is the full vertical field of view.

use glam::Vec3;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub position: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    /// Full vertical field of view in degrees.
    pub fov_y: f32,
}

/// The camera resolved for one film size: a ray through film point (x, y) (in pixels,
/// y down) has direction `forward + (2x/w − 1)·right + (1 − 2y/h)·up`, normalised.
/// `right` and `up` are pre-scaled by the half-extent of the image plane at distance 1.
/// The GPU ray generation kernels read exactly these three vectors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraFrame {
    pub origin: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        let forward = (self.look_at - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        // Re-orthogonalise up so a slightly tilted `up` does not shear the image.
        let up = right.cross(forward);
        let half_h = (self.fov_y.to_radians() * 0.5).tan();
        let half_w = half_h * width as f32 / height as f32;
        CameraFrame {
            origin: self.position,
            forward,
            right: right * half_w,
            up: up * half_h,
            width,
            height,
        }
    }
}

impl CameraFrame {
    /// origin, forward, right and up as the vec4s the GPU kernels read (w = 0).
    pub fn gpu_vectors(&self) -> [[f32; 4]; 4] {
        [self.origin, self.forward, self.right, self.up].map(|v| v.extend(0.0).into())
    }

    /// Unit direction of the ray through film point (x, y) in pixels (pixel centre at +0.5).
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        let sx = 2.0 * x / self.width as f32 - 1.0;
        let sy = 1.0 - 2.0 * y / self.height as f32;
        (self.forward + sx * self.right + sy * self.up).normalize()
    }

    /// Unit direction of the ray through the centre of pixel (px, py).
    pub fn pixel_center_direction(&self, px: u32, py: u32) -> Vec3 {
        self.direction(px as f32 + 0.5, py as f32 + 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera {
            position: Vec3::new(0.0, 0.0, -5.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 90.0,
        }
    }

    #[test]
    fn centre_ray_looks_forward_and_right_is_forward_cross_up() {
        let f = cam().frame(4, 2);
        let d = f.direction(2.0, 1.0);
        assert!((d - Vec3::Z).length() < 1e-6);
        // forward = +z, up = +y, so right = z × y = −x.
        assert!(f.right.normalize().abs_diff_eq(Vec3::NEG_X, 1e-6));
        // Row 0 is the top: the ray through y = 0 points up.
        assert!(f.direction(2.0, 0.0).y > 0.0);
        // fov 90° → the top edge is at 45°; aspect 2 widens the horizontal extent.
        assert!((f.up.length() - 1.0).abs() < 1e-6);
        assert!((f.right.length() - 2.0).abs() < 1e-6);
    }
}
