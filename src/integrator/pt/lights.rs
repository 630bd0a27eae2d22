//! The light table: emissive triangles and point lights, chosen in proportion to their
//! power (then a point uniformly by area on a triangle).
//!
//! Power: an emissive triangle is a one-sided Lambertian emitter facing its geometric
//! normal, Φ = π · luminance(Le) · area; a point light radiates Φ = 4π · luminance(I).
//! A light is chosen with probability Φ / ΣΦ (a discrete CDF searched on the GPU); for
//! multiple importance sampling the probability of having chosen a triangle is kept per
//! triangle (`tri_pmf`), and the shading kernel turns pmf / area into a solid-angle
//! density with dist² / cos θ_light.
//!
//! GPU films add values in f32, whose range (about 1e-38 to 3e38, squared values half
//! that in exponent) is narrower than the units scenes come in. Values are multiplied
//! by a power of two ([`LightTable::brightness_scale`]) that puts the brightest emitter
//! near 1 before they are added, and divided by it when read: the light vertex cache's
//! fixed-point splats, and the second moments of `pt` and the light vertex cache, whose
//! squares would otherwise overflow above about 1e19 and vanish below about 1e-22.

use glam::Vec3;

use super::gpu::{GpuLight, LIGHT_POINT, LIGHT_TRIANGLE};
use crate::scene::Scene;

/// The largest exponent [`LightTable::brightness_scale`] uses either way: 2^±100 and
/// the values it scales stay normal f32 numbers.
const SCALE_EXPONENT_LIMIT: i32 = 100;

/// Rec. 709 luminance.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.212_671, 0.715_160, 0.072_169))
}

/// Lights, their CDF and the per-triangle probability of choice.
#[derive(Clone, Debug, Default)]
pub struct LightTable {
    pub lights: Vec<GpuLight>,
    /// `cdf[k]` = P(choice ≤ k); the last entry is exactly 1.
    pub cdf: Vec<f32>,
    /// Probability of choosing each triangle (0 for non-emitters).
    pub tri_pmf: Vec<f32>,
    /// ΣΦ (W, luminance).
    pub total_power: f32,
}

impl LightTable {
    pub fn new(scene: &Scene) -> Self {
        let mut lights = Vec::new();
        let mut power = Vec::new();
        let mut tri_index = Vec::new();
        for (i, t) in scene.triangles.iter().enumerate() {
            let m = &scene.materials[t.material as usize];
            let area = t.area();
            let phi = std::f32::consts::PI * luminance(m.emission.max(Vec3::ZERO)) * area;
            if phi.is_nan() || phi <= 0.0 || t.is_degenerate() {
                continue;
            }
            let e1 = t.p[1] - t.p[0];
            let e2 = t.p[2] - t.p[0];
            lights.push(GpuLight {
                p0_type: t.p[0].extend(f32::from_bits(LIGHT_TRIANGLE)).into(),
                e1_area: e1.extend(area).into(),
                e2_tri: e2.extend(f32::from_bits(i as u32)).into(),
                emission_pmf: m.emission.extend(0.0).into(),
            });
            power.push(phi);
            tri_index.push(Some(i));
        }
        for l in &scene.point_lights {
            let phi = 4.0 * std::f32::consts::PI * luminance(l.intensity.max(Vec3::ZERO));
            if phi.is_nan() || phi <= 0.0 {
                continue;
            }
            lights.push(GpuLight {
                p0_type: l.position.extend(f32::from_bits(LIGHT_POINT)).into(),
                e1_area: [0.0; 4],
                e2_tri: [0.0; 4],
                emission_pmf: l.intensity.extend(0.0).into(),
            });
            power.push(phi);
            tri_index.push(None);
        }
        let total: f64 = power.iter().map(|&p| p as f64).sum();
        let mut cdf = Vec::with_capacity(power.len());
        let mut tri_pmf = vec![0.0f32; scene.triangles.len()];
        let mut running = 0.0f64;
        for (k, &p) in power.iter().enumerate() {
            let pmf = (p as f64 / total) as f32;
            running += p as f64;
            cdf.push((running / total) as f32);
            lights[k].emission_pmf[3] = pmf;
            if let Some(t) = tri_index[k] {
                tri_pmf[t] = pmf;
            }
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Self {
            lights,
            cdf,
            tri_pmf,
            total_power: total as f32,
        }
    }

    /// The power of two GPU films multiply values by before adding them: 2^-e, where
    /// 2^e is the brightest emitter's radiance rounded down to a power of two. A point
    /// light's intensity I counts as the radiance I / r² it gives at the scene's radius
    /// r. 1 without lights. Multiplying by a power of two is exact, so dividing by it
    /// again gives back every bit.
    pub fn brightness_scale(&self, scene_radius: f32) -> f32 {
        let brightest = self
            .lights
            .iter()
            .map(|l| {
                let emitted = l.emission_pmf[..3].iter().copied().fold(0.0f32, f32::max);
                if l.p0_type[3].to_bits() == LIGHT_POINT {
                    emitted / (scene_radius * scene_radius)
                } else {
                    emitted
                }
            })
            .filter(|&v| v.is_finite() && v > 0.0)
            .fold(0.0f32, f32::max);
        if brightest == 0.0 {
            return 1.0;
        }
        let exponent =
            (brightest.log2().floor() as i32).clamp(-SCALE_EXPONENT_LIMIT, SCALE_EXPONENT_LIMIT);
        2f32.powi(-exponent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_light_table() {
        let scene = crate::scene::builtin("cornell-box").unwrap();
        let t = LightTable::new(&scene);
        assert_eq!(t.lights.len(), 2);
        assert_eq!(*t.cdf.last().unwrap(), 1.0);
        let sum: f32 = t.tri_pmf.iter().sum();
        assert!((sum - 1.0).abs() < 1e-6);
        // The two triangles of the 130 × 105 light share its power by area.
        for l in &t.lights {
            assert!((l.emission_pmf[3] - 0.5).abs() < 1e-5);
            let n = Vec3::from_slice(&l.e1_area[..3]).cross(Vec3::from_slice(&l.e2_tri[..3]));
            assert!(n.y < 0.0, "the light faces down");
        }
    }

    #[test]
    fn the_brightness_scale_puts_the_brightest_emitter_near_one() {
        let mut scene = crate::scene::builtin("cornell-box").unwrap();
        let radius = scene.bounds().radius();
        // The Cornell light emits (17, 12, 4): 2^4 ≤ 17 < 2^5.
        assert_eq!(LightTable::new(&scene).brightness_scale(radius), 1.0 / 16.0);
        for m in &mut scene.materials {
            m.emission *= 1e-9;
        }
        let scale = LightTable::new(&scene).brightness_scale(radius);
        assert!((1.0..2.0).contains(&(17e-9 * scale)), "{scale}");
        for m in &mut scene.materials {
            m.emission = Vec3::ZERO;
        }
        assert_eq!(LightTable::new(&scene).brightness_scale(radius), 1.0);
    }
}
