//! Delta BSDFs: the perfect mirror and the smooth dielectric (Fresnel-weighted specular
//! reflection and transmission), plus the Fresnel and refraction helpers.

use super::{BsdfFlags, BsdfSample, TransportMode};
use glam::Vec3;

/// Unpolarized Fresnel reflectance of a dielectric interface for cos θ of the incident
/// direction against the normal of the +z side; η = η_inside / η_outside. Negative
/// `cos_i` means incidence from inside (η is then inverted). 1 under total internal
/// reflection. 0 for η = 1, exactly: no interface reflects nothing (the formula would
/// leave a rounding residue of cos θt against cos θi).
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    if eta == 1.0 {
        return 0.0;
    }
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (r_parl * r_parl + r_perp * r_perp) * 0.5
}

/// Schlick's approximation F0 + (1 − F0)(1 − cos)⁵.
pub fn fresnel_schlick(f0: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos.abs()).clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (Vec3::ONE - f0) * (m2 * m2 * m)
}

/// `w` reflected about `n` (both pointing away from the surface).
pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    -w + n * (2.0 * w.dot(n))
}

/// Refraction of `w` (pointing away) through the interface with normal `n` and
/// η = η_(−n side) / η_(n side). Returns the refracted direction and the relative index
/// η' = η_t / η_i of the crossing, or `None` under total internal reflection. For η = 1
/// exactly `-w`, whatever `n`: no interface bends nothing.
pub fn refract(w: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    if eta == 1.0 {
        return Some((-w, 1.0));
    }
    let mut cos_i = w.dot(n);
    let mut eta = eta;
    let mut n = n;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let wt = -w / eta + n * (cos_i / eta - cos_t);
    Some((wt, eta))
}

pub fn mirror_sample(tint: Vec3, wo: Vec3) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let wi = Vec3::new(-wo.x, -wo.y, wo.z);
    Some(BsdfSample {
        f: tint / wi.z.abs(),
        wi,
        pdf: 1.0,
        flags: BsdfFlags::REFLECTION | BsdfFlags::SPECULAR,
        eta: 1.0,
        layer: 0,
    })
}

/// Reflects with probability R = F(cos θo), else refracts; `uc` makes the choice.
pub fn dielectric_sample(
    tint: Vec3,
    eta: f32,
    wo: Vec3,
    uc: f32,
    mode: TransportMode,
) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let r = fresnel_dielectric(wo.z, eta);
    let t = 1.0 - r;
    if uc < r {
        let wi = Vec3::new(-wo.x, -wo.y, wo.z);
        return Some(BsdfSample {
            f: tint * (r / wi.z.abs()),
            wi,
            pdf: r,
            flags: BsdfFlags::REFLECTION | BsdfFlags::SPECULAR,
            eta: 1.0,
            layer: 0,
        });
    }
    let (wi, etap) = refract(wo, Vec3::Z, eta)?;
    if wi.z == 0.0 || t <= 0.0 {
        return None;
    }
    let mut ft = t / wi.z.abs();
    if mode == TransportMode::Radiance {
        ft /= etap * etap;
    }
    Some(BsdfSample {
        f: tint * ft,
        wi,
        pdf: t,
        flags: BsdfFlags::TRANSMISSION | BsdfFlags::SPECULAR,
        eta: etap,
        layer: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_limits() {
        let r0 = ((1.5f32 - 1.0) / 2.5).powi(2);
        assert!((fresnel_dielectric(1.0, 1.5) - r0).abs() < 1e-6);
        assert!((fresnel_dielectric(-1.0, 1.5) - r0).abs() < 1e-6);
        assert_eq!(fresnel_dielectric(-0.1, 1.5), 1.0); // total internal reflection
        assert!((fresnel_dielectric(1e-4, 1.5) - 1.0).abs() < 1e-3);
    }

    #[test]
    fn refraction_obeys_snell() {
        let w = Vec3::new(0.6, 0.0, 0.8);
        let (t, etap) = refract(w, Vec3::Z, 1.5).unwrap();
        assert_eq!(etap, 1.5);
        assert!((t.length() - 1.0).abs() < 1e-6);
        assert!(t.z < 0.0);
        assert!((0.6 - 1.5 * (1.0 - t.z * t.z).sqrt()).abs() < 1e-6);
        // and back
        let (back, etap2) = refract(t, Vec3::Z, 1.5).unwrap();
        assert!((back - w).length() < 1e-5 && (etap2 - 1.0 / 1.5).abs() < 1e-7);
    }
}
