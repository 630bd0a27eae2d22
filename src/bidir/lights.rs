//! Light sampling on the CPU, with exactly the semantics of `pt`'s light table
//! ([`LightTable`], `glsl/integrator/pt/shade.comp`): a light is chosen with probability
//! Φ / ΣΦ (emissive triangles and point lights alike), a point on a triangle uniformly by
//! area (the square-root warp of shade.comp), so the area density of a point is
//! `tri_pmf / area` and of a point light its discrete `pmf`.
//!
//! Emitters are one-sided Lambertian: a triangle emits its radiance `Le` towards the
//! side of its geometric normal only. Light subpaths leave a triangle with a
//! cosine-weighted direction about that normal (density cos θ / π) and a point light
//! with a uniform direction (1 / 4π). The same distribution serves next-event estimation
//! (s = 1) and the first vertex of light subpaths, so their position densities agree.

use glam::Vec3;

use super::positive;

use crate::bsdf::sampling::{cosine_hemisphere, uniform_sphere, uniform_sphere_pdf};
use crate::bsdf::Frame;
use crate::integrator::pt::gpu::{GpuLight, LIGHT_POINT};
use crate::integrator::pt::LightTable;

/// A point on a light: where a light subpath starts, or what next-event estimation aims
/// at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPoint {
    /// Index in the light table.
    pub light: u32,
    pub p: Vec3,
    /// Unit front normal of an emissive triangle; zero for a point light.
    pub n: Vec3,
    /// Radiance `Le` of a triangle, intensity `I` (W/sr) of a point light.
    pub radiance: Vec3,
    /// Density of choosing this point: pmf / area for a triangle (per unit area), the
    /// pmf for a point light (discrete: a delta in position).
    pub pdf_area: f32,
    /// A point light (its position is a delta: no path can hit it).
    pub delta: bool,
}

impl LightPoint {
    /// cos θ of the unit direction `dir` leaving the light: against the front normal,
    /// 1 for a point light.
    pub fn cos_out(&self, dir: Vec3) -> f32 {
        if self.delta {
            1.0
        } else {
            self.n.dot(dir)
        }
    }

    /// What the light sends along `dir` (radiance, or intensity for a point light):
    /// zero behind a triangle.
    pub fn emitted(&self, dir: Vec3) -> Vec3 {
        if self.cos_out(dir) > 0.0 {
            self.radiance
        } else {
            Vec3::ZERO
        }
    }

    /// Solid-angle density with which a light subpath leaves along `dir`.
    pub fn pdf_direction(&self, dir: Vec3) -> f32 {
        if self.delta {
            return uniform_sphere_pdf();
        }
        self.cos_out(dir).max(0.0) * std::f32::consts::FRAC_1_PI
    }
}

/// The start of a light subpath: a point, a direction and the subpath's throughput
/// `Le cos θ / (pdf_area · pdf_dir)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    pub point: LightPoint,
    pub dir: Vec3,
    pub pdf_dir: f32,
    pub weight: Vec3,
}

/// The light table seen from the CPU.
#[derive(Clone, Copy, Debug)]
pub struct Lights<'a> {
    table: &'a LightTable,
}

impl<'a> Lights<'a> {
    pub fn new(table: &'a LightTable) -> Self {
        Self { table }
    }

    pub fn is_empty(&self) -> bool {
        self.table.lights.is_empty()
    }

    pub fn len(&self) -> usize {
        self.table.lights.len()
    }

    /// The first light whose cumulative probability exceeds `u` (`pick_light` of
    /// shade.comp, the same binary search).
    pub fn pick(&self, u: f32) -> usize {
        let cdf = &self.table.cdf;
        let (mut lo, mut hi) = (0usize, cdf.len().saturating_sub(1));
        while lo < hi {
            let mid = (lo + hi) / 2;
            if u < cdf[mid] {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        lo
    }

    /// Probability of choosing light `k`.
    pub fn pmf(&self, k: usize) -> f32 {
        self.table.lights[k].emission_pmf[3]
    }

    /// The point of light `k` for (u1, u2) (ignored by point lights).
    pub fn point(&self, k: usize, u1: f32, u2: f32) -> Option<LightPoint> {
        let l: &GpuLight = &self.table.lights[k];
        let pmf = l.emission_pmf[3];
        let radiance = Vec3::from_slice(&l.emission_pmf[..3]);
        let origin = Vec3::from_slice(&l.p0_type[..3]);
        if l.p0_type[3].to_bits() == LIGHT_POINT {
            return (pmf > 0.0).then_some(LightPoint {
                light: k as u32,
                p: origin,
                n: Vec3::ZERO,
                radiance,
                pdf_area: pmf,
                delta: true,
            });
        }
        let (e1, e2) = (
            Vec3::from_slice(&l.e1_area[..3]),
            Vec3::from_slice(&l.e2_tri[..3]),
        );
        let area = l.e1_area[3];
        let su = u1.sqrt();
        let (b1, b2) = (1.0 - su, u2 * su);
        let n = e1.cross(e2).normalize_or_zero();
        (pmf > 0.0 && area > 0.0 && n != Vec3::ZERO).then_some(LightPoint {
            light: k as u32,
            p: origin + b1 * e1 + b2 * e2,
            n,
            radiance,
            pdf_area: pmf / area,
            delta: false,
        })
    }

    /// A light chosen by `u[0]`, a point on it by `u[1..]`.
    pub fn sample(&self, u: [f32; 3]) -> Option<LightPoint> {
        if self.is_empty() {
            return None;
        }
        self.point(self.pick(u[0]), u[1], u[2])
    }

    /// A light point (`u_point`) and a direction leaving it (`u_dir`): cosine-weighted
    /// about a triangle's normal, uniform for a point light.
    pub fn sample_emission(&self, u_point: [f32; 3], u_dir: [f32; 2]) -> Option<Emission> {
        let point = self.sample(u_point)?;
        let dir = if point.delta {
            uniform_sphere(u_dir[0], u_dir[1])
        } else {
            Frame::from_normal(point.n).to_world(cosine_hemisphere(u_dir[0], u_dir[1]))
        };
        let pdf_dir = point.pdf_direction(dir);
        let cos = point.cos_out(dir);
        if !positive(pdf_dir) || !positive(cos) {
            return None;
        }
        Some(Emission {
            point,
            dir,
            pdf_dir,
            weight: point.radiance * (cos / (point.pdf_area * pdf_dir)),
        })
    }

    /// The area density with which next-event estimation and light subpaths choose a
    /// point on emissive triangle `triangle` of area `area` (for a camera subpath that
    /// hit it).
    pub fn pdf_area_of_triangle(&self, triangle: u32, area: f32) -> f32 {
        let pmf = self.table.tri_pmf.get(triangle as usize).copied();
        match pmf {
            Some(pmf) if area > 0.0 => pmf / area,
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bidir::random::random01;
    use crate::bsdf::chi2::{self, Chi2Settings};
    use crate::scene::{builtin, PointLight};

    fn table() -> LightTable {
        let mut scene = builtin("cornell-box").unwrap();
        scene.point_lights.push(PointLight {
            position: Vec3::new(100.0, 400.0, 200.0),
            intensity: Vec3::new(2e4, 1e4, 5e3),
        });
        LightTable::new(&scene)
    }

    fn u(i: u32, d: u32) -> f32 {
        random01(i, 0, d, 17)
    }

    /// Pearson's χ² of observed against expected counts (no pooling needed: every
    /// expectation here is large).
    fn p_value(observed: &[f64], expected: &[f64], n: usize) -> f64 {
        chi2::chi2_test(observed, expected, n, 5.0).unwrap().p_value
    }

    #[test]
    fn lights_are_chosen_by_power() {
        let t = table();
        let lights = Lights::new(&t);
        assert_eq!(lights.len(), 3);
        let n = 200_000;
        let mut counts = vec![0.0; 3];
        for i in 0..n {
            counts[lights.pick(u(i, 0))] += 1.0;
        }
        let expected: Vec<f64> = (0..3).map(|k| lights.pmf(k) as f64 * n as f64).collect();
        let p = p_value(&counts, &expected, n as usize);
        assert!(p > 1e-3, "{counts:?} vs {expected:?}: p = {p}");
    }

    /// Points on a triangle are uniform by area: binned in (b1, b2 / (1 − b1)), whose
    /// densities are 2 (1 − b1) and uniform.
    #[test]
    fn triangle_points_are_uniform_and_their_density_is_pmf_over_area() {
        let t = table();
        let lights = Lights::new(&t);
        let l = &t.lights[0];
        let (p0, e1, e2) = (
            Vec3::from_slice(&l.p0_type[..3]),
            Vec3::from_slice(&l.e1_area[..3]),
            Vec3::from_slice(&l.e2_tri[..3]),
        );
        let (rows, cols) = (8usize, 8usize);
        let n = 200_000;
        let mut counts = vec![0.0; rows * cols];
        for i in 0..n {
            let q = lights.point(0, u(i, 1), u(i, 2)).unwrap();
            assert!((q.pdf_area - l.emission_pmf[3] / l.e1_area[3]).abs() < 1e-12);
            // Barycentrics of q from the edges (least squares, exact in the plane).
            let d = q.p - p0;
            let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
            let (r1, r2) = (d.dot(e1), d.dot(e2));
            let det = a * c - b * b;
            let b1 = ((c * r1 - b * r2) / det).clamp(0.0, 1.0);
            let b2 = ((a * r2 - b * r1) / det).clamp(0.0, 1.0);
            let v = if b1 < 1.0 { b2 / (1.0 - b1) } else { 0.0 };
            let row = ((b1 * rows as f32) as usize).min(rows - 1);
            let col = ((v * cols as f32) as usize).min(cols - 1);
            counts[row * cols + col] += 1.0;
        }
        let expected: Vec<f64> = (0..rows * cols)
            .map(|k| {
                let (lo, hi) = (
                    (k / cols) as f64 / rows as f64,
                    (k / cols + 1) as f64 / rows as f64,
                );
                n as f64 * ((1.0 - lo).powi(2) - (1.0 - hi).powi(2)) / cols as f64
            })
            .collect();
        let p = p_value(&counts, &expected, n as usize);
        assert!(p > 1e-3, "p = {p}");
    }

    /// Emitted directions follow their density (χ² over the sphere), for a triangle
    /// (cos θ / π about its normal, none behind it) and a point light (uniform).
    #[test]
    fn emission_directions_follow_their_density() {
        let t = table();
        let lights = Lights::new(&t);
        let s = Chi2Settings::default();
        for k in [0usize, 2] {
            let point = lights.point(k, 0.3, 0.6).unwrap();
            let n = 100_000;
            let dirs = (0..n).map(|i| {
                let e = lights
                    .sample_emission([lights_cdf_mid(&lights, k), 0.3, 0.6], [u(i, 3), u(i, 4)])
                    .unwrap();
                assert_eq!(e.point, point);
                assert!((e.pdf_dir - point.pdf_direction(e.dir)).abs() < 1e-6);
                Some(e.dir)
            });
            let observed = chi2::histogram(dirs, &s);
            let pdf = |w: Vec3| point.pdf_direction(w) as f64;
            let expected = chi2::expected_frequencies(&pdf, n as usize, &s);
            let out = chi2::chi2_test(&observed, &expected, n as usize, s.min_expected).unwrap();
            assert!((out.expected_mass - 1.0).abs() < 1e-3, "{out:?}");
            assert!(out.p_value > 1e-3, "light {k}: {out:?}");
        }
    }

    /// A `u` that picks light `k`.
    fn lights_cdf_mid(lights: &Lights, k: usize) -> f32 {
        let lo = if k == 0 { 0.0 } else { lights.table.cdf[k - 1] };
        0.5 * (lo + lights.table.cdf[k])
    }

    #[test]
    fn emitters_are_one_sided_and_points_are_deltas() {
        let t = table();
        let lights = Lights::new(&t);
        let tri = lights.point(0, 0.2, 0.2).unwrap();
        assert!(!tri.delta && tri.n.y < 0.0);
        assert_eq!(tri.emitted(Vec3::Y), Vec3::ZERO);
        assert_eq!(tri.emitted(-Vec3::Y), tri.radiance);
        assert_eq!(tri.pdf_direction(Vec3::Y), 0.0);
        let point = lights.point(2, 0.2, 0.2).unwrap();
        assert!(point.delta && point.pdf_area == lights.pmf(2));
        assert_eq!(point.emitted(Vec3::Y), point.radiance);
        let tri_index = t.lights[0].e2_tri[3].to_bits();
        let area = t.lights[0].e1_area[3];
        assert_eq!(lights.pdf_area_of_triangle(tri_index, area), tri.pdf_area);
        assert_eq!(lights.pdf_area_of_triangle(0, 1.0), 0.0);
    }
}
