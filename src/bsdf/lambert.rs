//! Lambertian reflection (two-sided): f = albedo / π, cosine-weighted sampling.

use super::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Whether `wo` and `wi` lie strictly on the same side of the surface.
pub fn same_hemisphere(wo: Vec3, wi: Vec3) -> bool {
    wo.z * wi.z > 0.0
}

pub fn eval(albedo: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    if !same_hemisphere(wo, wi) {
        return Vec3::ZERO;
    }
    albedo * FRAC_1_PI
}

/// Cosine-hemisphere pdf on `wo`'s side (shared by Oren–Nayar).
pub fn pdf(wo: Vec3, wi: Vec3) -> f32 {
    if !same_hemisphere(wo, wi) {
        return 0.0;
    }
    cosine_hemisphere_pdf(wi.z)
}

/// A cosine-distributed direction on `wo`'s side.
pub fn sample_wi(wo: Vec3, u1: f32, u2: f32) -> Option<Vec3> {
    if wo.z == 0.0 {
        return None;
    }
    let mut wi = cosine_hemisphere(u1, u2);
    if wo.z < 0.0 {
        wi.z = -wi.z;
    }
    (wi.z != 0.0).then_some(wi)
}
