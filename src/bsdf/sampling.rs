//! Warps from [0, 1)² to directions, mirrored by `glsl/common/sampling.glsl`.

use glam::Vec3;
use std::f32::consts::PI;

/// The largest f32 below 1 (random numbers are clamped to [0, ONE_MINUS_EPSILON]).
pub const ONE_MINUS_EPSILON: f32 = 0.999_999_94;

/// Cosine-weighted direction on the +z hemisphere (polar mapping: r = √u1, φ = 2πu2).
pub fn cosine_hemisphere(u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let z = (1.0 - u1).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// pdf of [`cosine_hemisphere`] for a direction with cos θ = `cos_theta`.
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.abs() * (1.0 / PI)
}

/// Uniform direction on the unit sphere.
pub fn uniform_sphere(u1: f32, u2: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// pdf of [`uniform_sphere`].
pub fn uniform_sphere_pdf() -> f32 {
    1.0 / (4.0 * PI)
}

/// Direction from cos θ and φ (θ from +z).
pub fn spherical_direction(cos_theta: f32, phi: f32) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warps_give_unit_vectors() {
        for i in 0..64 {
            let (u1, u2) = ((i % 8) as f32 / 8.0, (i / 8) as f32 / 8.0);
            assert!((cosine_hemisphere(u1, u2).length() - 1.0).abs() < 1e-5);
            assert!(cosine_hemisphere(u1, u2).z >= 0.0);
            assert!((uniform_sphere(u1, u2).length() - 1.0).abs() < 1e-5);
        }
    }
}
