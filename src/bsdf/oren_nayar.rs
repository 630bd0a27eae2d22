//! Oren–Nayar diffuse reflection, the qualitative model as in pbrt-v3 (σ in radians),
//! two-sided, sampled like Lambertian. The qualitative model is not exactly energy
//! conserving: its white-furnace albedo reaches ~1.013 at grazing incidence (θo = 87°,
//! σ = 0.2) and stays ≤ 1 for cos θo ≥ 0.3 (`tests/bsdf_chi2.rs`).

use super::lambert::same_hemisphere;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// The model's A and B terms for roughness σ (radians).
pub fn coefficients(sigma: f32) -> (f32, f32) {
    let s2 = sigma * sigma;
    (1.0 - s2 / (2.0 * (s2 + 0.33)), 0.45 * s2 / (s2 + 0.09))
}

pub fn eval(albedo: Vec3, sigma: f32, wo: Vec3, wi: Vec3) -> Vec3 {
    if !same_hemisphere(wo, wi) {
        return Vec3::ZERO;
    }
    let (a, b) = coefficients(sigma);
    let sin_i = (1.0 - wi.z * wi.z).max(0.0).sqrt();
    let sin_o = (1.0 - wo.z * wo.z).max(0.0).sqrt();
    let mut max_cos = 0.0f32;
    if sin_i > 1e-4 && sin_o > 1e-4 {
        let (cpi, spi) = (
            (wi.x / sin_i).clamp(-1.0, 1.0),
            (wi.y / sin_i).clamp(-1.0, 1.0),
        );
        let (cpo, spo) = (
            (wo.x / sin_o).clamp(-1.0, 1.0),
            (wo.y / sin_o).clamp(-1.0, 1.0),
        );
        max_cos = (cpi * cpo + spi * spo).max(0.0);
    }
    let (sin_alpha, tan_beta) = if wi.z.abs() > wo.z.abs() {
        (sin_o, sin_i / wi.z.abs())
    } else {
        (sin_i, sin_o / wo.z.abs())
    };
    albedo * (FRAC_1_PI * (a + b * max_cos * sin_alpha * tan_beta))
}
