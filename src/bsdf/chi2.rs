//! Pearson χ² goodness-of-fit of a direction sampler against its pdf, in the style of
//! pbrt's `bsdfs_test.cpp`: directions are binned in (θ, φ), the pdf is integrated over
//! each bin numerically, low-expectation bins are pooled, and the statistic's p-value is
//! compared with a (Šidák-corrected) significance level.

use glam::Vec3;
use std::f64::consts::PI;

/// Binning and test settings.
#[derive(Clone, Copy, Debug)]
pub struct Chi2Settings {
    /// Bins over θ ∈ [0, π] (the +z/−z boundary falls on a bin edge when even).
    pub theta_res: usize,
    /// Bins over φ ∈ [0, 2π).
    pub phi_res: usize,
    /// Initial quadrature cells per bin and dimension (refined adaptively).
    pub subdivisions: usize,
    /// Bins expecting fewer samples are pooled.
    pub min_expected: f64,
}

impl Default for Chi2Settings {
    fn default() -> Self {
        Self {
            theta_res: 10,
            phi_res: 20,
            subdivisions: 4,
            min_expected: 5.0,
        }
    }
}

/// The outcome of one test.
#[derive(Clone, Copy, Debug)]
pub struct Chi2Outcome {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// Sum of the expected frequencies over the number of samples drawn: the fraction
    /// of the pdf's mass on the sphere.
    pub expected_mass: f64,
}

/// The bin of a unit direction.
pub fn bin_of(w: Vec3, s: &Chi2Settings) -> usize {
    let theta = (w.z as f64).clamp(-1.0, 1.0).acos();
    let mut phi = (w.y as f64).atan2(w.x as f64);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let ti = ((theta / PI * s.theta_res as f64) as usize).min(s.theta_res - 1);
    let pi = ((phi / (2.0 * PI) * s.phi_res as f64) as usize).min(s.phi_res - 1);
    ti * s.phi_res + pi
}

/// Counts of directions per bin (`None`s, failed samples, are not counted).
pub fn histogram(dirs: impl IntoIterator<Item = Option<Vec3>>, s: &Chi2Settings) -> Vec<f64> {
    let mut h = vec![0.0; s.theta_res * s.phi_res];
    for w in dirs.into_iter().flatten() {
        h[bin_of(w, s)] += 1.0;
    }
    h
}

/// `n_samples` × ∫_bin pdf dω for every bin, by adaptive cubature in (θ, φ): each bin
/// starts as `subdivisions`² cells; a cell's 3×3-point Gauss–Legendre estimate is
/// compared with the sum over its four quadrants, which are refined recursively until
/// the two agree to 1e-9 of the sphere's measure (or 12 levels deep). Nodes are interior,
/// so a pdf that jumps at a bin edge, such as at the horizon, is integrated on the
/// correct side, and narrow near-specular lobes are resolved.
pub fn expected_frequencies(
    pdf: &dyn Fn(Vec3) -> f64,
    n_samples: usize,
    s: &Chi2Settings,
) -> Vec<f64> {
    let m = s.subdivisions.max(1);
    let dt = PI / s.theta_res as f64;
    let dp = 2.0 * PI / s.phi_res as f64;
    let mut out = Vec::with_capacity(s.theta_res * s.phi_res);
    for ti in 0..s.theta_res {
        for pi in 0..s.phi_res {
            let (ht, hp) = (dt / m as f64, dp / m as f64);
            let mut sum = 0.0;
            for a in 0..m {
                for b in 0..m {
                    let t0 = ti as f64 * dt + a as f64 * ht;
                    let p0 = pi as f64 * dp + b as f64 * hp;
                    let whole = cell(pdf, t0, t0 + ht, p0, p0 + hp);
                    sum += adaptive(pdf, [t0, t0 + ht, p0, p0 + hp], whole, 0);
                }
            }
            out.push(sum * n_samples as f64);
        }
    }
    out
}

/// 3×3 Gauss–Legendre estimate of ∫∫ pdf sinθ dθ dφ over one cell.
fn cell(pdf: &dyn Fn(Vec3) -> f64, t0: f64, t1: f64, p0: f64, p1: f64) -> f64 {
    let g = (3.0f64 / 5.0).sqrt();
    const W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let x = [-g, 0.0, g];
    let (tm, th) = (0.5 * (t0 + t1), 0.5 * (t1 - t0));
    let (pm, ph) = (0.5 * (p0 + p1), 0.5 * (p1 - p0));
    let mut sum = 0.0;
    for i in 0..3 {
        let (st, ct) = (tm + th * x[i]).sin_cos();
        for j in 0..3 {
            let (sp, cp) = (pm + ph * x[j]).sin_cos();
            let w = Vec3::new((st * cp) as f32, (st * sp) as f32, ct as f32);
            sum += W[i] * W[j] * pdf(w) * st;
        }
    }
    sum * th * ph
}

fn adaptive(pdf: &dyn Fn(Vec3) -> f64, c: [f64; 4], whole: f64, depth: u32) -> f64 {
    let [t0, t1, p0, p1] = c;
    let (tm, pm) = (0.5 * (t0 + t1), 0.5 * (p0 + p1));
    let quads = [
        [t0, tm, p0, pm],
        [t0, tm, pm, p1],
        [tm, t1, p0, pm],
        [tm, t1, pm, p1],
    ];
    let parts = quads.map(|q| cell(pdf, q[0], q[1], q[2], q[3]));
    let split: f64 = parts.iter().sum();
    if depth >= 12 || (split - whole).abs() <= 1e-9 {
        return split;
    }
    quads
        .iter()
        .zip(parts)
        .map(|(q, part)| adaptive(pdf, *q, part, depth + 1))
        .sum()
}

/// Pearson's test of `observed` against `expected` (pbrt-v3's pooling rule).
/// Errs when samples fall in a bin of zero expectation.
pub fn chi2_test(
    observed: &[f64],
    expected: &[f64],
    n_samples: usize,
    min_expected: f64,
) -> Result<Chi2Outcome, String> {
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pooled_exp, mut pooled_obs, mut pooled) = (0.0, 0.0, 0usize);
    let (mut stat, mut dof) = (0.0, 0usize);
    for &i in &order {
        if expected[i] == 0.0 {
            if observed[i] > n_samples as f64 * 1e-5 {
                return Err(format!(
                    "{} samples in bin {i}, where the pdf integrates to 0",
                    observed[i]
                ));
            }
        } else if expected[i] < min_expected || (pooled_exp > 0.0 && pooled_exp < min_expected) {
            pooled_exp += expected[i];
            pooled_obs += observed[i];
            pooled += 1;
        } else {
            let d = observed[i] - expected[i];
            stat += d * d / expected[i];
            dof += 1;
        }
    }
    if pooled > 0 && pooled_exp > 0.0 {
        let d = pooled_obs - pooled_exp;
        stat += d * d / pooled_exp;
        dof += 1;
    }
    let dof = dof.saturating_sub(1);
    let p_value = if dof == 0 {
        1.0
    } else {
        gamma_q(dof as f64 / 2.0, stat / 2.0)
    };
    Ok(Chi2Outcome {
        statistic: stat,
        dof,
        p_value,
        expected_mass: expected.iter().sum::<f64>() / n_samples as f64,
    })
}

/// Šidák-corrected per-test significance for `tests` tests at family level `alpha`.
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests as f64)
}

fn ln_gamma(x: f64) -> f64 {
    // Lanczos (g = 7, n = 9).
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularized upper incomplete gamma Q(a, x) (Numerical Recipes §6.2).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let gln = ln_gamma(a);
    if x < a + 1.0 {
        let (mut ap, mut sum) = (a, 1.0 / a);
        let mut del = sum;
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - gln).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - gln).exp() * h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_q_matches_known_chi2_quantiles() {
        // χ² with k dof: P(X > x) = Q(k/2, x/2).
        assert!((gamma_q(0.5, 3.841_458_8 / 2.0) - 0.05).abs() < 1e-6);
        assert!((gamma_q(5.0, 23.209_251 / 2.0) - 0.01).abs() < 1e-6);
        assert!((gamma_q(99.5, 242.0 / 2.0) - 0.0217).abs() < 2e-3); // k = 199
        assert!((gamma_q(1.0, 2.0) - (-2.0f64).exp()).abs() < 1e-12);
    }

    #[test]
    fn uniform_sphere_passes_and_a_wrong_pdf_fails() {
        use crate::bsdf::sampling::uniform_sphere;
        let s = Chi2Settings::default();
        let n = 100_000;
        // Hashed (not stratified) uniforms, so the statistic behaves as for i.i.d.
        let mut state = 0u64;
        let dirs = (0..n).map(|_| {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut h = state;
            h = (h ^ (h >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            h = (h ^ (h >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            h ^= h >> 31;
            let a = ((h >> 40) as f32) / (1u64 << 24) as f32;
            let b = (((h >> 16) & 0xFF_FFFF) as f32) / (1u64 << 24) as f32;
            Some(uniform_sphere(a, b))
        });
        let obs = histogram(dirs, &s);
        let good = expected_frequencies(&|_| 1.0 / (4.0 * PI), n, &s);
        let r = chi2_test(&obs, &good, n, 5.0).unwrap();
        assert!((r.expected_mass - 1.0).abs() < 1e-6);
        assert!(r.p_value > 1e-4, "{r:?}");
        let bad = expected_frequencies(&|w| (1.0 + 0.1 * w.z as f64) / (4.0 * PI), n, &s);
        assert!(chi2_test(&obs, &bad, n, 5.0).unwrap().p_value < 1e-6);
    }
}
