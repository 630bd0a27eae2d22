//! CPU tests of the BSDFs: χ² goodness of fit of `sample` against `pdf` for every
//! non-delta BSDF over a spread of parameters, sample/eval/pdf consistency,
//! reciprocity, and white-furnace energy checks.

use crate::common::SplitMix64 as Rng;

use glam::Vec3;
use rayon::prelude::*;
use splitray::bsdf::chi2::{self, Chi2Settings};
use splitray::bsdf::microfacet::blinn_phong_exponent;
use splitray::bsdf::sampling::spherical_direction;
use splitray::bsdf::{Bsdf, BsdfParams, Distribution, TransportMode};

/// The draws these tests take besides uniforms.
trait Draws {
    fn u3(&mut self) -> [f32; 3];
    fn sphere(&mut self) -> Vec3;
}

impl Draws for Rng {
    fn u3(&mut self) -> [f32; 3] {
        [self.uniform(), self.uniform(), self.uniform()]
    }
    fn sphere(&mut self) -> Vec3 {
        splitray::bsdf::sampling::uniform_sphere(self.uniform(), self.uniform())
    }
}

const DISTRIBUTIONS: [Distribution; 3] = [
    Distribution::BlinnPhong,
    Distribution::Beckmann,
    Distribution::Ggx,
];

/// The distribution's parameter for a Beckmann-equivalent α.
fn roughness(dist: Distribution, alpha: f32) -> f32 {
    if dist == Distribution::BlinnPhong {
        blinn_phong_exponent(alpha)
    } else {
        alpha
    }
}

fn wo_at(cos_theta: f32) -> Vec3 {
    spherical_direction(cos_theta, 0.7)
}

struct Case {
    name: String,
    params: BsdfParams,
    wo: Vec3,
}

fn case(name: String, params: BsdfParams, wo: Vec3) -> Case {
    Case { name, params, wo }
}

/// Every non-delta configuration the χ² test covers.
fn chi2_cases() -> Vec<Case> {
    let angles = [0.98f32, 0.55, 0.08];
    let white = Vec3::ONE;
    let mut cases = vec![];
    for &c in &angles {
        let b = Bsdf::Lambert { albedo: white };
        cases.push(case(format!("lambert cos {c}"), b.params(), wo_at(c)));
        for sigma in [0.25f32, 0.6] {
            let b = Bsdf::OrenNayar {
                albedo: white,
                sigma,
            };
            cases.push(case(
                format!("oren-nayar σ {sigma} cos {c}"),
                b.params(),
                wo_at(c),
            ));
        }
        for dist in DISTRIBUTIONS {
            for alpha in [0.05f32, 0.3, 0.8] {
                let b = Bsdf::MicrofacetReflection {
                    f0: Vec3::new(0.9, 0.6, 0.3),
                    distribution: dist,
                    roughness: roughness(dist, alpha),
                };
                cases.push(case(
                    format!("microfacet reflection {dist:?} α {alpha} cos {c}"),
                    b.params(),
                    wo_at(c),
                ));
                for eta in [1.5f32, 1.0 / 1.5] {
                    let b = Bsdf::MicrofacetDielectric {
                        tint: white,
                        distribution: dist,
                        roughness: roughness(dist, alpha),
                        eta,
                    };
                    cases.push(case(
                        format!("rough dielectric {dist:?} α {alpha} η {eta:.3} cos {c}"),
                        b.params(),
                        wo_at(c),
                    ));
                }
            }
        }
    }
    // wo below the surface (inside the dielectric / back side of reflectors).
    for (dist, alpha) in [(Distribution::Ggx, 0.3f32), (Distribution::Beckmann, 0.5)] {
        let b = Bsdf::MicrofacetDielectric {
            tint: white,
            distribution: dist,
            roughness: alpha,
            eta: 1.33,
        };
        cases.push(case(
            format!("rough dielectric {dist:?} α {alpha} η 1.33, wo below"),
            b.params(),
            wo_at(-0.6),
        ));
        let b = Bsdf::MicrofacetReflection {
            f0: white,
            distribution: dist,
            roughness: alpha,
        };
        cases.push(case(
            format!("microfacet reflection {dist:?} α {alpha}, wo below"),
            b.params(),
            wo_at(-0.4),
        ));
    }
    // Layered stacks, delta layers included (their samples carry no direction density
    // and are excluded from the histogram, exactly as their mass is absent from pdf).
    for (i, p) in layered_stacks().into_iter().enumerate() {
        for &c in &[0.9f32, 0.3] {
            cases.push(case(format!("layered #{i} cos {c}"), p, wo_at(c)));
        }
    }
    cases
}

fn layered_stacks() -> Vec<BsdfParams> {
    let white = Vec3::ONE;
    vec![
        // glossy paint: diffuse base + glossy coat
        BsdfParams::layered(&[
            (Bsdf::Lambert { albedo: white }, 0.6),
            (
                Bsdf::MicrofacetReflection {
                    f0: white,
                    distribution: Distribution::Ggx,
                    roughness: 0.1,
                },
                0.4,
            ),
        ]),
        // four layers with a delta one: Oren–Nayar, Beckmann, mirror, Blinn–Phong
        BsdfParams::layered(&[
            (
                Bsdf::OrenNayar {
                    albedo: white,
                    sigma: 0.4,
                },
                0.3,
            ),
            (
                Bsdf::MicrofacetReflection {
                    f0: Vec3::new(0.8, 0.5, 0.2),
                    distribution: Distribution::Beckmann,
                    roughness: 0.4,
                },
                0.3,
            ),
            (Bsdf::Mirror { tint: white }, 0.2),
            (
                Bsdf::MicrofacetReflection {
                    f0: white,
                    distribution: Distribution::BlinnPhong,
                    roughness: 50.0,
                },
                0.2,
            ),
        ]),
        // frosted glass over a diffuse layer, plus a specular dielectric
        BsdfParams::layered(&[
            (
                Bsdf::MicrofacetDielectric {
                    tint: white,
                    distribution: Distribution::Ggx,
                    roughness: 0.2,
                    eta: 1.5,
                },
                0.5,
            ),
            (Bsdf::Lambert { albedo: white }, 0.25),
            (
                Bsdf::Dielectric {
                    tint: white,
                    eta: 1.5,
                },
                0.25,
            ),
        ]),
    ]
}

const SAMPLES: usize = 200_000;

#[test]
fn chi2_sample_matches_pdf_for_every_non_delta_bsdf() {
    let cases = chi2_cases();
    let settings = Chi2Settings::default();
    let alpha = chi2::sidak(0.01, cases.len());
    let mode = TransportMode::Radiance;
    let results: Vec<(String, Result<chi2::Chi2Outcome, String>)> = cases
        .par_iter()
        .enumerate()
        .map(|(i, c)| {
            let mut rng = Rng(1000 + i as u64);
            let dirs = (0..SAMPLES).map(|_| {
                c.params
                    .sample(c.wo, rng.u3(), mode)
                    .filter(|s| !s.flags.is_specular())
                    .map(|s| s.wi)
            });
            let observed = chi2::histogram(dirs, &settings);
            let expected = chi2::expected_frequencies(
                &|wi| c.params.pdf(c.wo, wi, mode) as f64,
                SAMPLES,
                &settings,
            );
            (
                c.name.clone(),
                chi2::chi2_test(&observed, &expected, SAMPLES, settings.min_expected),
            )
        })
        .collect();
    let mut failures = vec![];
    let mut min_p = 1.0f64;
    for (name, r) in &results {
        match r {
            Ok(o) => {
                min_p = min_p.min(o.p_value);
                if o.p_value < alpha || o.expected_mass > 1.0 + 2e-3 {
                    failures.push(format!("{name}: {o:?}"));
                }
            }
            Err(e) => failures.push(format!("{name}: {e}")),
        }
    }
    eprintln!(
        "χ²: {} configurations, {SAMPLES} samples each, Šidák level {alpha:.2e}, smallest p {min_p:.3e}, {} failed",
        results.len(),
        failures.len()
    );
    assert!(failures.is_empty(), "χ² failures:\n{}", failures.join("\n"));
}

#[test]
fn sample_returns_eval_and_pdf() {
    let mut rng = Rng(7);
    for c in chi2_cases() {
        for mode in [TransportMode::Radiance, TransportMode::Importance] {
            for _ in 0..500 {
                let Some(s) = c.params.sample(c.wo, rng.u3(), mode) else {
                    continue;
                };
                assert!((s.wi.length() - 1.0).abs() < 1e-4, "{}", c.name);
                if s.flags.is_specular() {
                    continue;
                }
                let f = c.params.eval(c.wo, s.wi, mode);
                let pdf = c.params.pdf(c.wo, s.wi, mode);
                assert!(
                    s.pdf > 0.0 && (s.pdf - pdf).abs() <= 1e-5 * pdf,
                    "{}",
                    c.name
                );
                assert!(
                    (s.f - f).abs().max_element() <= 1e-5 * f.max_element(),
                    "{}",
                    c.name
                );
            }
        }
    }
}

fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-7
}

#[test]
fn reflection_bsdfs_are_reciprocal() {
    let mut rng = Rng(11);
    let mut bsdfs = vec![
        Bsdf::Lambert {
            albedo: Vec3::new(0.2, 0.5, 0.9),
        }
        .params(),
        Bsdf::OrenNayar {
            albedo: Vec3::ONE,
            sigma: 0.5,
        }
        .params(),
    ];
    for dist in DISTRIBUTIONS {
        for alpha in [0.05f32, 0.3, 0.8] {
            bsdfs.push(
                Bsdf::MicrofacetReflection {
                    f0: Vec3::new(0.9, 0.2, 0.5),
                    distribution: dist,
                    roughness: roughness(dist, alpha),
                }
                .params(),
            );
        }
    }
    bsdfs.push(layered_stacks()[1]);
    let mut checked = 0;
    for p in &bsdfs {
        for _ in 0..4000 {
            let (wo, mut wi) = (rng.sphere(), rng.sphere());
            if wo.z * wi.z < 0.0 {
                wi.z = -wi.z;
            }
            for mode in [TransportMode::Radiance, TransportMode::Importance] {
                let a = p.eval(wo, wi, mode);
                let b = p.eval(wi, wo, mode);
                for k in 0..3 {
                    assert!(close(a[k], b[k], 1e-4), "{p:?}\n{wo} {wi}: {a} vs {b}");
                }
            }
            checked += 1;
        }
    }
    assert!(checked > 10_000);
}

/// Rough dielectric: in Radiance mode f(wo, wi)/η_o² = f(wi, wo)/η_i² (η_o: the index on
/// wo's side; Veach eq. 5.14), and the Importance-mode BSDF is the adjoint,
/// f_imp(wo, wi) = f_rad(wi, wo). Reflection (both on one side) is plainly symmetric.
#[test]
fn rough_dielectric_obeys_generalized_reciprocity() {
    let mut rng = Rng(12);
    let mut worst = 0.0f32;
    for dist in DISTRIBUTIONS {
        for alpha in [0.05f32, 0.3, 0.8] {
            for eta in [1.5f32, 1.0 / 1.33] {
                let p = Bsdf::MicrofacetDielectric {
                    tint: Vec3::ONE,
                    distribution: dist,
                    roughness: roughness(dist, alpha),
                    eta,
                }
                .params();
                let mut nonzero = 0;
                for t in 0..3000 {
                    // Half the pairs uniform, half importance-sampled (near-specular
                    // lobes are rarely hit by uniform pairs).
                    let wo = rng.sphere();
                    let mut wi = rng.sphere();
                    if t % 2 == 0 {
                        if let Some(s) = p.sample(wo, rng.u3(), TransportMode::Radiance) {
                            wi = s.wi;
                        }
                    }
                    let index = |w: Vec3| if w.z > 0.0 { 1.0 } else { eta };
                    let (n_o, n_i) = (index(wo), index(wi));
                    let fr = p.eval(wo, wi, TransportMode::Radiance).x;
                    let br = p.eval(wi, wo, TransportMode::Radiance).x;
                    let fi = p.eval(wo, wi, TransportMode::Importance).x;
                    let a = fr / (n_o * n_o);
                    let b = br / (n_i * n_i);
                    // The half vector is rebuilt from (wo, wi) in f32; the transmission
                    // denominator (wi·m + wo·m/η')² cancels near its pole: allow 5e-4.
                    assert!(
                        close(a, b, 5e-4),
                        "{dist:?} α {alpha} η {eta} {wo} {wi}: {a} vs {b}"
                    );
                    assert!(
                        close(fi, br, 5e-4),
                        "adjoint {dist:?} {wo} {wi}: {fi} vs {br}"
                    );
                    if a > 1e-3 {
                        worst = worst.max((a - b).abs() / a.max(b));
                        nonzero += 1;
                    }
                }
                assert!(
                    nonzero > 300,
                    "{dist:?} α {alpha} η {eta}: too few nonzero pairs"
                );
            }
        }
    }
    eprintln!("generalized reciprocity: worst relative difference {worst:.2e}");
}

/// Monte Carlo albedo ∫ f |cos θi| dωi by importance sampling: mean and standard error.
fn albedo(p: &BsdfParams, wo: Vec3, mode: TransportMode, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = Rng(seed);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        if let Some(s) = p.sample(wo, rng.u3(), mode) {
            let w = (s.f.x * s.wi.z.abs() / s.pdf) as f64;
            sum += w;
            sum2 += w * w;
        }
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(0.0);
    (mean, (var / n as f64).sqrt())
}

#[test]
fn white_furnace() {
    let n = 100_000;
    let white = Vec3::ONE;
    let imp = TransportMode::Importance;
    let rad = TransportMode::Radiance;
    let angles = [0.99f32, 0.7, 0.3, 0.05];
    let mut report = vec![];
    let mut failures = vec![];
    for (ci, &c) in angles.iter().enumerate() {
        let wo = wo_at(c);
        let seed = 100 + ci as u64;
        // Lossless: exactly 1 per sample.
        for (name, p) in [
            ("lambert", Bsdf::Lambert { albedo: white }.params()),
            ("mirror", Bsdf::Mirror { tint: white }.params()),
            (
                "dielectric η 1.5",
                Bsdf::Dielectric {
                    tint: white,
                    eta: 1.5,
                }
                .params(),
            ),
            (
                "dielectric η 1/1.5",
                Bsdf::Dielectric {
                    tint: white,
                    eta: 1.0 / 1.5,
                }
                .params(),
            ),
            (
                "lambert + mirror",
                BsdfParams::layered(&[
                    (Bsdf::Lambert { albedo: white }, 0.5),
                    (Bsdf::Mirror { tint: white }, 0.5),
                ]),
            ),
        ] {
            let (a, _) = albedo(&p, wo, imp, n, seed);
            assert!((a - 1.0).abs() < 1e-4, "{name} cos {c}: albedo {a}");
        }
        // Radiance mode: transmitted radiance is scaled by 1/η'²: E = R + T/η².
        let eta = 1.5f32;
        let p = Bsdf::Dielectric { tint: white, eta }.params();
        let r = splitray::bsdf::specular::fresnel_dielectric(c, eta) as f64;
        let (a, se) = albedo(&p, wo, rad, n, seed);
        let want = r + (1.0 - r) / (eta as f64 * eta as f64);
        assert!(
            (a - want).abs() < 4.0 * se + 1e-4,
            "radiance dielectric {a} vs {want}"
        );
        // Lossy or approximate models: ≤ 1 (within 4 standard errors).
        let mut lossy: Vec<(String, BsdfParams)> = vec![];
        for sigma in [0.2f32, 0.5, 1.0] {
            if c < 0.1 {
                continue; // grazing Oren–Nayar: checked separately below
            }
            lossy.push((
                format!("oren-nayar σ {sigma}"),
                Bsdf::OrenNayar {
                    albedo: white,
                    sigma,
                }
                .params(),
            ));
        }
        for dist in DISTRIBUTIONS {
            for alpha in [0.05f32, 0.3, 0.8] {
                if dist == Distribution::BlinnPhong && alpha > 0.3 {
                    continue; // Walter's Λ mapping is inaccurate there: see below
                }
                let rough = roughness(dist, alpha);
                lossy.push((
                    format!("microfacet {dist:?} α {alpha}"),
                    Bsdf::MicrofacetReflection {
                        f0: white,
                        distribution: dist,
                        roughness: rough,
                    }
                    .params(),
                ));
                for eta in [1.5f32, 1.0 / 1.5] {
                    lossy.push((
                        format!("rough dielectric {dist:?} α {alpha} η {eta:.3}"),
                        Bsdf::MicrofacetDielectric {
                            tint: white,
                            distribution: dist,
                            roughness: rough,
                            eta,
                        }
                        .params(),
                    ));
                }
            }
        }
        for (name, p) in &lossy {
            let (a, se) = albedo(p, wo, imp, n, seed);
            if a > 1.0 + 4.0 * se + 1e-4 {
                failures.push(format!("{name} cos {c}: albedo {a} ± {se} > 1"));
            }
            // Near-specular microfacets lose almost nothing away from grazing.
            if name.contains("α 0.05") && c > 0.5 && a < 0.97 {
                failures.push(format!("{name} cos {c}: albedo {a} ± {se} too low"));
            }
            report.push(format!("{name} cos {c}: {a:.4}"));
        }
        let (a, se) = albedo(&Bsdf::Lambert { albedo: white }.params(), wo, rad, n, seed);
        assert!((a - 1.0).abs() < 1e-4, "lambert radiance {a} ± {se}");
    }
    // Known excesses of the prescribed models, bounded so that a regression shows:
    // the qualitative Oren–Nayar model gains up to ~1.5% at grazing incidence, and
    // Blinn–Phong with a very low exponent (n ≈ 1, α = 0.8) has no exact Smith Λ, so the
    // Beckmann Λ of Walter's mapping under-shadows it (up to ~27% gain at θo = 87°).
    let grazing = wo_at(0.05);
    for sigma in [0.2f32, 0.5, 1.0] {
        let p = Bsdf::OrenNayar {
            albedo: white,
            sigma,
        }
        .params();
        let (a, se) = albedo(&p, grazing, imp, n, 9);
        report.push(format!("oren-nayar σ {sigma} cos 0.05 (grazing): {a:.4}"));
        if a > 1.02 + 4.0 * se {
            failures.push(format!("oren-nayar σ {sigma} grazing: albedo {a} ± {se}"));
        }
    }
    for &c in &angles {
        let p = Bsdf::MicrofacetReflection {
            f0: white,
            distribution: Distribution::BlinnPhong,
            roughness: roughness(Distribution::BlinnPhong, 0.8),
        }
        .params();
        let (a, se) = albedo(&p, wo_at(c), imp, n, 10);
        report.push(format!(
            "microfacet BlinnPhong α 0.8 (n 1.125) cos {c}: {a:.4}"
        ));
        let bound = if c < 0.1 { 1.35 } else { 1.0 };
        if a > bound + 4.0 * se + 1e-4 {
            failures.push(format!("blinn-phong n 1.125 cos {c}: albedo {a} ± {se}"));
        }
    }
    eprintln!("albedos:\n{}", report.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn shading_normal_correction_is_one_for_radiance_and_adjoint_for_importance() {
    use splitray::bsdf::shading_normal_correction;
    let ng = Vec3::Z;
    let ns = Vec3::new(0.2, 0.0, 1.0).normalize();
    let wo = Vec3::new(0.3, 0.4, 0.5).normalize();
    let wi = Vec3::new(-0.5, 0.1, 0.6).normalize();
    assert_eq!(
        shading_normal_correction(wo, wi, ns, ng, TransportMode::Radiance),
        1.0
    );
    let c = shading_normal_correction(wo, wi, ns, ng, TransportMode::Importance);
    let want = wo.dot(ns).abs() * wi.dot(ng).abs() / (wo.dot(ng).abs() * wi.dot(ns).abs());
    assert!((c - want).abs() < 1e-6);
    assert_eq!(
        shading_normal_correction(wo, wi, ns, ns, TransportMode::Importance),
        1.0
    );
}
