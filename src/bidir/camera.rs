//! The pinhole camera as a subpath vertex: its importance W_e, the density with which it
//! samples directions, and the projection of a direction onto the film.
//!
//! A pixel's value is the box-filtered radiance over the pixel's part of the image
//! plane at distance 1 in front of the pinhole (the convention of `scene::camera`):
//! I_j = (1/A_pix) ∫_pixel L(u) du, A_pix the pixel's area on that plane. A direction at
//! angle θ to the optical axis meets the plane at distance 1/cos θ, so
//! du = dω / cos³θ, and
//!
//! - the camera samples directions through pixel j with density
//!   p(ω) = 1 / (A_pix cos³θ) (uniform in the pixel: `pt`'s jitter);
//! - the importance of pixel j is W_e(ω) = 1 / (A_pix cos⁴θ) inside the pixel, 0
//!   elsewhere, so that ∫ W_e cos θ dω = 1 over the pixel and W_e cos θ / p(ω) = 1: a
//!   camera subpath starts with throughput 1.
//!
//! Light tracing (t = 1) reaches the camera from a light-subpath vertex: the vertex
//! contributes β f G W_e to the pixel it projects to, divided by the number of light
//! subpaths of the pass, since every light subpath of the pass is a sample of every
//! pixel (pbrt-v4#456, pbrt-r4#92: the importance carries the pixel's normalisation).

use glam::Vec3;

use crate::scene::CameraFrame;

/// A pinhole camera resolved for one film.
#[derive(Clone, Copy, Debug)]
pub struct PinholeCamera {
    pub frame: CameraFrame,
    /// Area of one pixel on the image plane at distance 1.
    pixel_area: f32,
}

impl PinholeCamera {
    pub fn new(frame: &CameraFrame) -> Self {
        let plane = 4.0 * frame.right.length() * frame.up.length();
        let pixels = frame.width as f32 * frame.height as f32;
        Self {
            frame: *frame,
            pixel_area: plane / pixels,
        }
    }

    pub fn position(&self) -> Vec3 {
        self.frame.origin
    }

    pub fn width(&self) -> u32 {
        self.frame.width
    }

    pub fn height(&self) -> u32 {
        self.frame.height
    }

    pub fn pixel_count(&self) -> usize {
        self.frame.width as usize * self.frame.height as usize
    }

    /// A pixel's area on the image plane at distance 1.
    pub fn pixel_area(&self) -> f32 {
        self.pixel_area
    }

    /// The direction through film point (`pixel` + `jitter`), jitter in [0, 1)²: the
    /// arithmetic of `glsl/integrator/pt/generate.comp`.
    pub fn ray_direction(&self, pixel: u32, jitter: [f32; 2]) -> Vec3 {
        let px = (pixel % self.frame.width) as f32;
        let py = (pixel / self.frame.width) as f32;
        self.frame.direction(px + jitter[0], py + jitter[1])
    }

    /// cos θ of a unit direction against the optical axis.
    pub fn cos_theta(&self, dir: Vec3) -> f32 {
        dir.dot(self.frame.forward)
    }

    /// Solid-angle density with which the camera samples the unit direction `dir` for
    /// the pixel it passes through (0 behind the camera).
    pub fn pdf_direction(&self, dir: Vec3) -> f32 {
        let c = self.cos_theta(dir);
        if c <= 0.0 {
            return 0.0;
        }
        1.0 / (self.pixel_area * c * c * c)
    }

    /// W_e of the pixel that the unit direction `dir` passes through (0 behind the
    /// camera; the caller finds the pixel with [`PinholeCamera::pixel_of`]).
    pub fn importance(&self, dir: Vec3) -> f32 {
        let c = self.cos_theta(dir);
        if c <= 0.0 {
            return 0.0;
        }
        1.0 / (self.pixel_area * c * c * c * c)
    }

    /// Film coordinates (pixels, y down) where the unit direction `dir` meets the image,
    /// or `None` behind the camera or outside the film.
    pub fn raster(&self, dir: Vec3) -> Option<[f32; 2]> {
        let c = self.cos_theta(dir);
        if c <= 0.0 {
            return None;
        }
        let on_plane = dir / c - self.frame.forward;
        let sx = on_plane.dot(self.frame.right) / self.frame.right.length_squared();
        let sy = on_plane.dot(self.frame.up) / self.frame.up.length_squared();
        let x = (sx + 1.0) * 0.5 * self.frame.width as f32;
        let y = (1.0 - sy) * 0.5 * self.frame.height as f32;
        let inside = (0.0..self.frame.width as f32).contains(&x)
            && (0.0..self.frame.height as f32).contains(&y);
        inside.then_some([x, y])
    }

    /// The pixel (row-major, row 0 at the top) that the unit direction `dir` passes
    /// through.
    pub fn pixel_of(&self, dir: Vec3) -> Option<u32> {
        let [x, y] = self.raster(dir)?;
        let px = (x as u32).min(self.frame.width - 1);
        let py = (y as u32).min(self.frame.height - 1);
        Some(py * self.frame.width + px)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bidir::random::random01;
    use crate::bsdf::sampling::{uniform_sphere, uniform_sphere_pdf};
    use crate::scene::Camera;

    fn camera(w: u32, h: u32) -> PinholeCamera {
        let c = Camera {
            position: Vec3::new(0.5, 1.0, -3.0),
            look_at: Vec3::new(0.0, 0.8, 1.0),
            up: Vec3::Y,
            fov_y: 50.0,
        };
        PinholeCamera::new(&c.frame(w, h))
    }

    /// Monte Carlo over uniform directions on the sphere: ∫ W_e cos θ dω over each of
    /// a few pixels, and ∫ p(ω) dω over the same pixels, are both 1 — W_e, the
    /// direction pdf and the projection agree with each other and with the pixel
    /// footprint.
    #[test]
    fn importance_and_pdf_integrate_to_one_over_a_pixel() {
        let cam = camera(8, 6);
        let pixels = [0u32, 13, 47];
        let n = 4_000_000u32;
        let mut we = [0.0f64; 3];
        let mut pdf = [0.0f64; 3];
        for i in 0..n {
            let d = uniform_sphere(random01(i, 0, 0, 5), random01(i, 0, 1, 5));
            let Some(p) = cam.pixel_of(d) else { continue };
            if let Some(k) = pixels.iter().position(|&q| q == p) {
                let inv = 1.0 / uniform_sphere_pdf() as f64;
                we[k] += (cam.importance(d) * cam.cos_theta(d)) as f64 * inv;
                pdf[k] += cam.pdf_direction(d) as f64 * inv;
            }
        }
        for k in 0..3 {
            let (w, p) = (we[k] / n as f64, pdf[k] / n as f64);
            // Each pixel sees ~1/600 of the sphere: ~6500 hits, ~1.2% noise.
            assert!(
                (w - 1.0).abs() < 0.05,
                "pixel {}: ∫ W_e cos = {w}",
                pixels[k]
            );
            assert!((p - 1.0).abs() < 0.05, "pixel {}: ∫ p = {p}", pixels[k]);
        }
    }

    #[test]
    fn sampled_directions_map_back_to_their_pixel() {
        let cam = camera(7, 5);
        for pixel in 0..35u32 {
            for (a, b) in [(0.01f32, 0.02f32), (0.5, 0.5), (0.98, 0.97)] {
                let d = cam.ray_direction(pixel, [a, b]);
                assert_eq!(cam.pixel_of(d), Some(pixel));
                let [x, y] = cam.raster(d).unwrap();
                let (px, py) = ((pixel % 7) as f32 + a, (pixel / 7) as f32 + b);
                assert!((x - px).abs() < 1e-3 && (y - py).abs() < 1e-3);
                // A camera subpath starts with throughput W_e cos θ / p = 1.
                let ratio = cam.importance(d) * cam.cos_theta(d) / cam.pdf_direction(d);
                assert!((ratio - 1.0).abs() < 1e-5);
            }
        }
        assert_eq!(cam.pixel_of(-cam.frame.forward), None);
        assert_eq!(cam.importance(-cam.frame.forward), 0.0);
    }
}
