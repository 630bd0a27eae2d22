//! Microfacet distributions with Smith shadowing, microfacet reflection and the rough
//! dielectric (Walter et al. 2007, in the form of pbrt-v4's `DielectricBxDF`).
//!
//! Choices:
//! - **Distributions** (isotropic): Blinn–Phong D = (n+2)/(2π) cosⁿθm (parameter: the
//!   exponent n), Beckmann and GGX/Trowbridge–Reitz (parameter: α).
//! - **Shadowing**: height-correlated Smith G(wo, wi) = 1 / (1 + Λ(wo) + Λ(wi)), and
//!   G1 = 1 / (1 + Λ). Λ is exact for GGX, (√(1 + α² tan²θ) − 1)/2, and for Beckmann,
//!   (erfc(a) … ) with a = 1/(α tanθ): Λ = e^(−a²)/(2a√π) − erfc(a)/2, with erfc from
//!   Abramowitz–Stegun 7.1.26 (|error| ≤ 1.5e-7), the same polynomial in GLSL (which has
//!   no erf). Blinn–Phong has no closed-form Λ; it uses Beckmann's Λ with Walter's
//!   mapping α = √(2 / (n + 2)). That Λ is not D's own, so for very low exponents the
//!   lobe is under-shadowed and can gain energy at grazing incidence (white-furnace
//!   albedo 1.27 at n = 1.125, θo = 87°; ≤ 1 for n ≥ 20; `tests/bsdf_chi2.rs`).
//! - **Sampling**: m ~ D(m)|cos θm| (not visible normals); samples whose microfacet faces
//!   away from `wo` are rejected (the pdf then integrates to less than 1, consistently).
//! - **η = 1**: a rough dielectric of η exactly 1 is no interface. Light passes straight
//!   through whatever the microfacet normal, so the lobe is a delta the microfacet BTDF
//!   cannot represent (its half vector wi + wo vanishes, and in f32 is a rounding
//!   residue pointing anywhere): as in pbrt-v4, it is the smooth dielectric of η 1, eval
//!   and pdf 0, every sample straight through with the tint (`Bsdf::sample_direction`).
//! - **Fresnel**: microfacet reflection uses Schlick with F0 = the layer's rgb (a tinted
//!   conductor-like lobe, F0 = 1 is a lossless white reflector); the rough dielectric uses
//!   the exact unpolarized dielectric Fresnel and chooses reflection with probability F.

use super::lambert::same_hemisphere;
use super::specular::{fresnel_dielectric, fresnel_schlick, reflect, refract};
use super::{BsdfFlags, BsdfSample, TransportMode};
use glam::Vec3;
use std::f32::consts::PI;

/// Microfacet normal distribution (`BsdfLayer::distribution`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Distribution {
    /// Parameter: the Phong exponent n ≥ 0.
    BlinnPhong = 0,
    /// Parameter: α > 0.
    Beckmann = 1,
    /// GGX / Trowbridge–Reitz. Parameter: α > 0.
    Ggx = 2,
}

impl Distribution {
    pub fn from_u32(v: u32) -> Option<Self> {
        match v {
            0 => Some(Self::BlinnPhong),
            1 => Some(Self::Beckmann),
            2 => Some(Self::Ggx),
            _ => None,
        }
    }
}

/// Walter et al. 2007's Blinn–Phong exponent → Beckmann α, α = √(2 / (n + 2)).
pub fn blinn_phong_alpha(exponent: f32) -> f32 {
    (2.0 / (exponent + 2.0)).sqrt()
}

/// The inverse of [`blinn_phong_alpha`]: n = 2/α² − 2.
pub fn blinn_phong_exponent(alpha: f32) -> f32 {
    2.0 / (alpha * alpha) - 2.0
}

/// tan²θ as (x² + y²)/z²: no cancellation near the pole, and invariant to the rounding
/// of a normalization (important for peaked lobes, where D amplifies input error).
fn tan2_theta(w: Vec3) -> f32 {
    (w.x * w.x + w.y * w.y) / (w.z * w.z)
}

/// ln cos²θ: ln(1 − sin²θ) by its series near the pole (f32 has no log1p), ln z²
/// elsewhere (1 − sin²θ would cancel near the horizon).
fn ln_cos2_theta(w: Vec3) -> f32 {
    let s2 = w.x * w.x + w.y * w.y;
    if s2 < 0.01 {
        -s2 * (1.0 + s2 * (0.5 + s2 * (1.0 / 3.0 + s2 * (0.25 + s2 * 0.2))))
    } else {
        (w.z * w.z).max(1e-30).ln()
    }
}

/// D(m), for m in the +z hemisphere (0 below).
pub fn d(dist: Distribution, a: f32, m: Vec3) -> f32 {
    if m.z <= 0.0 {
        return 0.0;
    }
    match dist {
        // cosⁿθ = exp(n/2 · ln cos²θ), accurate for large n near the peak.
        Distribution::BlinnPhong => (a + 2.0) * (0.5 / PI) * (0.5 * a * ln_cos2_theta(m)).exp(),
        Distribution::Beckmann => {
            let cos2 = m.z * m.z;
            let tan2 = tan2_theta(m);
            if tan2.is_infinite() {
                return 0.0;
            }
            let a2 = a * a;
            (-tan2 / a2).exp() / (PI * a2 * cos2 * cos2)
        }
        Distribution::Ggx => {
            let cos2 = m.z * m.z;
            let tan2 = tan2_theta(m);
            if tan2.is_infinite() {
                return 0.0;
            }
            let a2 = a * a;
            let e = 1.0 + tan2 / a2;
            1.0 / (PI * a2 * cos2 * cos2 * e * e)
        }
    }
}

/// erfc(x) for x ≥ 0, Abramowitz–Stegun 7.1.26.
pub fn erfc_approx(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly = t
        * (0.254_829_6
            + t * (-0.284_496_72 + t * (1.421_413_8 + t * (-1.453_152 + t * 1.061_405_4))));
    poly * (-x * x).exp()
}

/// Smith Λ(w) of the distribution.
pub fn lambda(dist: Distribution, a: f32, w: Vec3) -> f32 {
    let tan2 = tan2_theta(w);
    if tan2.is_infinite() || tan2.is_nan() {
        return 0.0;
    }
    match dist {
        Distribution::Ggx => ((1.0 + a * a * tan2).sqrt() - 1.0) * 0.5,
        Distribution::Beckmann | Distribution::BlinnPhong => {
            let alpha = if dist == Distribution::Beckmann {
                a
            } else {
                blinn_phong_alpha(a)
            };
            let tan = tan2.sqrt();
            if tan == 0.0 {
                return 0.0;
            }
            let x = 1.0 / (alpha * tan);
            let l = (-x * x).exp() * (0.5 / PI.sqrt()) / x - 0.5 * erfc_approx(x);
            l.max(0.0)
        }
    }
}

/// Smith masking G1(w) = 1 / (1 + Λ(w)).
pub fn g1(dist: Distribution, a: f32, w: Vec3) -> f32 {
    1.0 / (1.0 + lambda(dist, a, w))
}

/// Height-correlated Smith masking-shadowing G(wo, wi) = 1 / (1 + Λ(wo) + Λ(wi)).
pub fn g(dist: Distribution, a: f32, wo: Vec3, wi: Vec3) -> f32 {
    1.0 / (1.0 + lambda(dist, a, wo) + lambda(dist, a, wi))
}

/// Samples m in the +z hemisphere with density D(m) cos θm. sin²θm is computed without
/// cancellation (m near the pole matters for peaked lobes).
pub fn sample_m(dist: Distribution, a: f32, u1: f32, u2: f32) -> Vec3 {
    let (sin_theta, cos_theta) = match dist {
        Distribution::BlinnPhong => {
            // cos^(n+2) θ = u1, so ln cos²θ = l and sin²θ = −expm1(l).
            let l = 2.0 * u1.ln() / (a + 2.0);
            let sin2 = if l > -0.01 {
                -l * (1.0 + l * (0.5 + l * (1.0 / 6.0 + l * (1.0 / 24.0 + l * (1.0 / 120.0)))))
            } else {
                1.0 - l.exp()
            };
            (sin2.max(0.0).sqrt(), (1.0 - sin2).max(0.0).sqrt())
        }
        Distribution::Beckmann | Distribution::Ggx => {
            let tan2 = if dist == Distribution::Beckmann {
                -(a * a) * (1.0 - u1).ln()
            } else {
                a * a * u1 / (1.0 - u1)
            };
            let cos_theta = 1.0 / (1.0 + tan2).sqrt();
            (tan2.sqrt() * cos_theta, cos_theta)
        }
    };
    let phi = 2.0 * PI * u2;
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

/// Density of [`sample_m`]: D(m) cos θm.
pub fn pdf_m(dist: Distribution, a: f32, m: Vec3) -> f32 {
    d(dist, a, m) * m.z.abs()
}

/// Flips `wo`, `wi` to the +z side when `wo` is below (two-sided reflection).
fn upper(wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
    if wo.z < 0.0 {
        (
            wo * Vec3::new(1.0, 1.0, -1.0),
            wi * Vec3::new(1.0, 1.0, -1.0),
        )
    } else {
        (wo, wi)
    }
}

pub fn reflection_eval(f0: Vec3, dist: Distribution, a: f32, wo: Vec3, wi: Vec3) -> Vec3 {
    if !same_hemisphere(wo, wi) {
        return Vec3::ZERO;
    }
    let (wo, wi) = upper(wo, wi);
    let wm = wo + wi;
    if wm.length_squared() == 0.0 {
        return Vec3::ZERO;
    }
    let wm = wm.normalize();
    let f = fresnel_schlick(f0, wi.dot(wm));
    f * (d(dist, a, wm) * g(dist, a, wo, wi) / (4.0 * wi.z * wo.z))
}

pub fn reflection_pdf(dist: Distribution, a: f32, wo: Vec3, wi: Vec3) -> f32 {
    if !same_hemisphere(wo, wi) {
        return 0.0;
    }
    let (wo, wi) = upper(wo, wi);
    let wm = wo + wi;
    if wm.length_squared() == 0.0 {
        return 0.0;
    }
    let wm = wm.normalize();
    pdf_m(dist, a, wm) / (4.0 * wo.dot(wm).abs())
}

/// The sampled direction only (f and pdf come from eval and pdf).
pub fn reflection_sample_wi(
    dist: Distribution,
    a: f32,
    wo: Vec3,
    u1: f32,
    u2: f32,
) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let flip = Vec3::new(1.0, 1.0, if wo.z < 0.0 { -1.0 } else { 1.0 });
    let wo_up = wo * flip;
    let m = sample_m(dist, a, u1, u2);
    if wo_up.dot(m) <= 0.0 {
        return None;
    }
    let wi = reflect(wo_up, m);
    if wi.z <= 0.0 {
        return None;
    }
    Some(BsdfSample {
        f: Vec3::ZERO,
        wi: wi * flip,
        pdf: 0.0,
        flags: BsdfFlags::REFLECTION | BsdfFlags::GLOSSY,
        eta: 1.0,
        layer: 0,
    })
}

/// The microfacet normal of a rough-dielectric pair and the relative index η' of the
/// event (1 for reflection), or `None` when the pair has no valid, front-facing m.
fn dielectric_half(eta: f32, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32, bool)> {
    let (cos_o, cos_i) = (wo.z, wi.z);
    if cos_o == 0.0 || cos_i == 0.0 {
        return None;
    }
    let reflect = cos_i * cos_o > 0.0;
    let etap = if reflect {
        1.0
    } else if cos_o > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let wm = wi * etap + wo;
    if wm.length_squared() == 0.0 {
        return None;
    }
    let mut wm = wm.normalize();
    if wm.z < 0.0 {
        wm = -wm;
    }
    if wm.dot(wi) * cos_i <= 0.0 || wm.dot(wo) * cos_o <= 0.0 {
        return None;
    }
    Some((wm, etap, reflect))
}

/// F at the microfacet m for the pair: evaluated from the side of the optically
/// thinner medium (the same value in exact arithmetic, but near total internal
/// reflection 1 − F seen from the denser side cancels badly in f32).
fn fresnel_pair(eta: f32, wo: Vec3, wi: Vec3, wm: Vec3, etap: f32) -> f32 {
    if etap < 1.0 {
        fresnel_dielectric(wi.dot(wm), eta)
    } else {
        fresnel_dielectric(wo.dot(wm), eta)
    }
}

pub fn dielectric_eval(
    tint: Vec3,
    dist: Distribution,
    a: f32,
    eta: f32,
    wo: Vec3,
    wi: Vec3,
    mode: TransportMode,
) -> Vec3 {
    // η = 1: a delta lobe only (see the module docs).
    if eta == 1.0 {
        return Vec3::ZERO;
    }
    let Some((wm, etap, reflect)) = dielectric_half(eta, wo, wi) else {
        return Vec3::ZERO;
    };
    let f = fresnel_pair(eta, wo, wi, wm, etap);
    let dg = d(dist, a, wm) * g(dist, a, wo, wi);
    if reflect {
        return tint * (dg * f / (4.0 * wi.z * wo.z).abs());
    }
    let denom = wi.dot(wm) + wo.dot(wm) / etap;
    let denom = denom * denom;
    let mut ft = dg * (1.0 - f) * (wi.dot(wm) * wo.dot(wm) / (wi.z * wo.z * denom)).abs();
    if mode == TransportMode::Radiance {
        ft /= etap * etap;
    }
    tint * ft
}

pub fn dielectric_pdf(dist: Distribution, a: f32, eta: f32, wo: Vec3, wi: Vec3) -> f32 {
    if eta == 1.0 {
        return 0.0;
    }
    let Some((wm, etap, reflect)) = dielectric_half(eta, wo, wi) else {
        return 0.0;
    };
    let r = fresnel_pair(eta, wo, wi, wm, etap);
    let pm = pdf_m(dist, a, wm);
    if reflect {
        return pm / (4.0 * wo.dot(wm).abs()) * r;
    }
    let denom = wi.dot(wm) + wo.dot(wm) / etap;
    pm * (wi.dot(wm).abs() / (denom * denom)) * (1.0 - r)
}

/// The sampled direction only (f and pdf come from eval and pdf): m ~ D cos, then
/// reflection with probability F(wo·m), else refraction through m. Not for η = 1, which
/// samples the smooth dielectric (see the module docs).
pub fn dielectric_sample_wi(
    dist: Distribution,
    a: f32,
    eta: f32,
    wo: Vec3,
    u: [f32; 3],
) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let m = sample_m(dist, a, u[1], u[2]);
    let cos_om = wo.dot(m);
    if cos_om * wo.z <= 0.0 {
        return None;
    }
    let r = fresnel_dielectric(cos_om, eta);
    if u[0] < r {
        let wi = reflect(wo, m);
        if wi.z * wo.z <= 0.0 {
            return None;
        }
        return Some(BsdfSample {
            f: Vec3::ZERO,
            wi,
            pdf: 0.0,
            flags: BsdfFlags::REFLECTION | BsdfFlags::GLOSSY,
            eta: 1.0,
            layer: 0,
        });
    }
    let (wi, etap) = refract(wo, m, eta)?;
    if wi.z * wo.z >= 0.0 {
        return None;
    }
    Some(BsdfSample {
        f: Vec3::ZERO,
        wi,
        pdf: 0.0,
        flags: BsdfFlags::TRANSMISSION | BsdfFlags::GLOSSY,
        eta: etap,
        layer: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::sampling::spherical_direction;

    /// ∫ D(m) cos θm dm = 1 (projected area normalization), by quadrature in cos θ.
    #[test]
    fn distributions_are_normalized() {
        for (dist, a) in [
            (Distribution::BlinnPhong, 1.0),
            (Distribution::BlinnPhong, 30.0),
            (Distribution::Beckmann, 0.2),
            (Distribution::Beckmann, 0.8),
            (Distribution::Ggx, 0.2),
            (Distribution::Ggx, 0.8),
        ] {
            let n = 200_000;
            let mut sum = 0.0f64;
            for i in 0..n {
                let c = (i as f64 + 0.5) / n as f64;
                let m = spherical_direction(c as f32, 0.0);
                sum += d(dist, a, m) as f64 * c;
            }
            let integral = sum / n as f64 * 2.0 * std::f64::consts::PI;
            assert!((integral - 1.0).abs() < 5e-3, "{dist:?} {a}: {integral}");
        }
    }

    #[test]
    fn beckmann_lambda_matches_erf_series() {
        // Reference erfc by numerical integration in f64.
        for x in [0.05f64, 0.3, 1.0, 1.7, 3.0] {
            let n = 100_000;
            let h = (x + 8.0 - x) / n as f64;
            let mut s = 0.0;
            for i in 0..n {
                let t = x + (i as f64 + 0.5) * h;
                s += (-t * t).exp();
            }
            let erfc = s * h * 2.0 / std::f64::consts::PI.sqrt();
            assert!((erfc_approx(x as f32) as f64 - erfc).abs() < 3e-7, "{x}");
        }
        // Λ → 0 at normal incidence, large at grazing.
        assert_eq!(lambda(Distribution::Beckmann, 0.3, Vec3::Z), 0.0);
        let grazing = spherical_direction(0.01, 0.0);
        assert!(lambda(Distribution::Beckmann, 0.5, grazing) > 10.0);
    }
}
