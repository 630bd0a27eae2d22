//! [`FilmSums`]: what every integrator accumulates, pass by pass.
//!
//! A *pass* adds `samples_per_pass` samples to every pixel and yields one estimate of
//! each pixel (the mean of its samples in that pass, plus whatever light tracing splatted
//! there, normalised per pass). Passes are independent and identically distributed, so
//! the per-pixel sums of the pass estimates and of their squares give both the image
//! (their mean) and its standard error — for integrators whose samples within a pass are
//! correlated (CBPT) as much as for one-sample passes (`pt`). Sums are `f64`: integrators
//! that accumulate on the GPU, in pairs of `f32` ([`compensated`]), convert exactly, so
//! a film can be saved and restored without changing a bit. The GPU's second moments
//! are of estimates multiplied by a power of two (the square of an f32 estimate leaves
//! f32's range above about 1e19 and below about 1e-22); the conversions take it out and
//! put it back exactly.

use super::{compensated, Film, FilmError};

/// Per-pixel sums of the pass estimates (row 0 at the top, `y * width + x`).
#[derive(Clone, Debug, PartialEq)]
pub struct FilmSums {
    pub width: u32,
    pub height: u32,
    /// Passes accumulated.
    pub passes: u32,
    /// Samples per pixel that one pass adds.
    pub samples_per_pass: u32,
    /// Σ over passes of each pixel's estimate (RGB).
    pub sum: Vec<[f64; 3]>,
    /// Σ over passes of the squared estimates, where the integrator keeps them.
    pub sum_sq: Option<Vec<[f64; 3]>>,
}

impl FilmSums {
    /// Empty sums of `width × height` pixels; `second_moments` keeps Σ estimate².
    pub fn new(width: u32, height: u32, samples_per_pass: u32, second_moments: bool) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            passes: 0,
            samples_per_pass,
            sum: vec![[0.0; 3]; n],
            sum_sq: second_moments.then(|| vec![[0.0; 3]; n]),
        }
    }

    /// Starts keeping Σ estimate² from here on where the sums had none (a restored film
    /// of an integrator that keeps them: its standard error then covers the new passes).
    pub fn keep_second_moments(&mut self) {
        if self.sum_sq.is_none() {
            self.sum_sq = Some(vec![[0.0; 3]; self.sum.len()]);
        }
    }

    /// Sums of GPU accumulators, each a film of sums and remainders
    /// ([`compensated`]): `sum` holds Σ L in rgb (its w is
    /// ignored), `sum_sq` Σ (s L)² in rgb, s = `moment_scale`, a power of two
    /// ([`LightTable::brightness_scale`]; 1 where there are no second moments).
    ///
    /// [`LightTable::brightness_scale`]: crate::integrator::pt::LightTable::brightness_scale
    pub fn from_gpu(
        width: u32,
        height: u32,
        passes: u32,
        samples_per_pass: u32,
        sum: &[[f32; 4]],
        sum_sq: Option<&[[f32; 4]]>,
        moment_scale: f32,
    ) -> Self {
        // 1 / s² is a power of two of f64's range (s is at most 2^±100), so dividing by
        // it is exact.
        let unscale = 1.0 / squared_scale(moment_scale);
        Self {
            width,
            height,
            passes,
            samples_per_pass,
            sum: compensated::film_rgb(sum, 1.0),
            sum_sq: sum_sq.map(|q| compensated::film_rgb(q, unscale)),
        }
    }

    /// The sums as the GPU accumulators hold them (`w` of the first = passes), second
    /// moments at `moment_scale` as [`FilmSums::from_gpu`] takes them. Exact for sums
    /// that came from [`FilmSums::from_gpu`] at the same scale.
    pub fn to_gpu(&self, moment_scale: f32) -> (Vec<[f32; 4]>, Option<Vec<[f32; 4]>>) {
        let scale = squared_scale(moment_scale);
        (
            compensated::film_of(&self.sum, 1.0, self.passes as f64),
            self.sum_sq
                .as_deref()
                .map(|q| compensated::film_of(q, scale, 0.0)),
        )
    }

    pub fn pixel_count(&self) -> usize {
        self.sum.len()
    }

    /// Samples per pixel so far.
    pub fn spp(&self) -> u64 {
        self.passes as u64 * self.samples_per_pass as u64
    }

    /// Adds one pass: `estimate[p]` is pixel p's estimate from that pass.
    pub fn add_pass(&mut self, estimate: &[[f64; 3]]) {
        assert_eq!(estimate.len(), self.sum.len(), "pass of the wrong size");
        for (s, e) in self.sum.iter_mut().zip(estimate) {
            for c in 0..3 {
                s[c] += e[c];
            }
        }
        if let Some(q) = &mut self.sum_sq {
            for (q, e) in q.iter_mut().zip(estimate) {
                for c in 0..3 {
                    q[c] += e[c] * e[c];
                }
            }
        }
        self.passes += 1;
    }

    /// Per-pixel mean of the pass estimates (black before the first pass).
    pub fn mean(&self) -> Vec<[f32; 3]> {
        let n = self.passes.max(1) as f64;
        self.sum.iter().map(|s| s.map(|v| (v / n) as f32)).collect()
    }

    /// Per-pixel standard error of [`FilmSums::mean`], from the passes' sample variance;
    /// `None` without second moments or with fewer than two passes.
    pub fn stderr(&self) -> Option<Vec<[f32; 3]>> {
        let q = self.sum_sq.as_ref()?;
        if self.passes < 2 {
            return None;
        }
        let n = self.passes as f64;
        Some(
            self.sum
                .iter()
                .zip(q)
                .map(|(s, q)| {
                    let mut se = [0.0f32; 3];
                    for c in 0..3 {
                        let m = s[c] / n;
                        let var = (q[c] / n - m * m).max(0.0) * n / (n - 1.0);
                        se[c] = (var / n).sqrt() as f32;
                    }
                    se
                })
                .collect(),
        )
    }

    /// Adds another render's sums of the same image (another shard, a resumed part):
    /// the merged mean weights each part by its passes.
    pub fn merge(&mut self, other: &FilmSums) -> Result<(), String> {
        if (other.width, other.height) != (self.width, self.height) {
            return Err(format!(
                "film size {}x{} differs from {}x{}",
                other.width, other.height, self.width, self.height
            ));
        }
        if other.samples_per_pass != self.samples_per_pass {
            return Err(format!(
                "{} samples per pass differ from {}",
                other.samples_per_pass, self.samples_per_pass
            ));
        }
        for (s, o) in self.sum.iter_mut().zip(&other.sum) {
            for c in 0..3 {
                s[c] += o[c];
            }
        }
        self.sum_sq = match (self.sum_sq.take(), &other.sum_sq) {
            (Some(mut q), Some(o)) => {
                for (q, o) in q.iter_mut().zip(o) {
                    for c in 0..3 {
                        q[c] += o[c];
                    }
                }
                Some(q)
            }
            _ => None,
        };
        self.passes += other.passes;
        Ok(())
    }

    /// The image as a [`Film`] (mean per pixel, no AOVs).
    pub fn to_film(&self) -> Result<Film, FilmError> {
        Film::from_mean_rgb(self.width, self.height, &self.mean())
    }
}

/// s², exact in f64 for any power of two s of f32's range.
fn squared_scale(s: f32) -> f64 {
    let s = s as f64;
    s * s
}

/// ε of [`relative_mse`]: the usual guard against dividing by black pixels (Rousselle
/// et al. 2011).
pub const RELATIVE_MSE_GUARD: f64 = 0.01;

/// Relative mean squared error of `image` against `reference`: the mean over pixels
/// and channels of (v − r)² / (r² + ε), ε = [`RELATIVE_MSE_GUARD`]. `None` when the
/// sizes differ.
pub fn relative_mse(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Option<f64> {
    if image.len() != reference.len() || image.is_empty() {
        return None;
    }
    Some(relative_channel_mean(image, reference, |v, r| {
        (v - r) * (v - r)
    }))
}

/// The mean over pixels and channels of `term(x, r)` / (r² + ε), r from `reference`,
/// x the same pixel's channel in `values`: how the relative MSE weights a squared error.
pub(super) fn relative_channel_mean(
    values: &[[f32; 3]],
    reference: &[[f32; 3]],
    term: impl Fn(f64, f64) -> f64,
) -> f64 {
    let total: f64 = values
        .iter()
        .zip(reference)
        .flat_map(|(v, r)| (0..3).map(move |c| (v[c] as f64, r[c] as f64)))
        .map(|(x, r)| term(x, r) / (r * r + RELATIVE_MSE_GUARD))
        .sum();
    total / (3 * reference.len()).max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_stderr_of_passes() {
        let mut s = FilmSums::new(2, 1, 1, true);
        s.add_pass(&[[1.0, 2.0, 3.0], [0.0; 3]]);
        s.add_pass(&[[3.0, 2.0, 1.0], [0.0; 3]]);
        assert_eq!(s.mean(), vec![[2.0, 2.0, 2.0], [0.0; 3]]);
        let se = s.stderr().unwrap();
        // Sample variance of {1, 3} is 2; the stderr of the mean of two is 1.
        assert!((se[0][0] - 1.0).abs() < 1e-6);
        assert_eq!(se[0][1], 0.0);
        assert_eq!(se[1], [0.0; 3]);
    }

    #[test]
    fn gpu_round_trip_is_exact() {
        // Two pixels' sums, then their remainders.
        let sum = [
            [0.1f32, 1e30, -3.5e-20, 4.0],
            [7.0, 8.0, 9.0, 4.0],
            [1.0e-9, 2.0e22, 0.0, 0.0],
            [0.0, -2.0f32.powi(-30), 0.0, 0.0],
        ];
        let sq = [
            [0.3f32, 2.0, 5.0, 0.0],
            [1.0, 1.0, 1.0, 0.0],
            [0.0; 4],
            [0.0; 4],
        ];
        let s = FilmSums::from_gpu(2, 1, 4, 1, &sum, Some(&sq), 1.0);
        let (back, back_sq) = s.to_gpu(1.0);
        assert_eq!(back, sum.to_vec());
        assert_eq!(back_sq.unwrap(), sq.to_vec());
    }

    #[test]
    fn scaled_second_moments_come_back_unscaled_and_round_trip_exactly() {
        // Two passes of estimates about 2^70 and 2^-80, whose squares leave f32's range,
        // with their second moments summed at the scales that bring them near 1.
        for (exponent, scale) in [(70, 2f32.powi(-70)), (-80, 2f32.powi(80))] {
            let unit = 2f64.powi(exponent);
            let mut expected = FilmSums::new(2, 1, 1, true);
            expected.add_pass(&[[unit, 2.0 * unit, 0.0], [0.0; 3]]);
            expected.add_pass(&[[3.0 * unit, 2.0 * unit, 0.0], [0.0; 3]]);
            let u = unit as f32;
            let sum = [
                [4.0 * u, 4.0 * u, 0.0, 2.0],
                [0.0, 0.0, 0.0, 2.0],
                [0.0; 4],
                [0.0; 4],
            ];
            let sq = [
                [1.0 + 9.0, 4.0 + 4.0, 0.0, 0.0],
                [0.0; 4],
                [0.0; 4],
                [0.0; 4],
            ];
            let got = FilmSums::from_gpu(2, 1, 2, 1, &sum, Some(&sq), scale);
            assert_eq!(got, expected, "2^{exponent}");
            // The estimates 1 and 3 (× 2^k) have a standard error of the mean of 1.
            assert_eq!(got.stderr().unwrap()[0], [u, 0.0, 0.0], "2^{exponent}");
            let (back, back_sq) = got.to_gpu(scale);
            assert_eq!((back, back_sq.unwrap()), (sum.to_vec(), sq.to_vec()));
        }
    }

    #[test]
    fn merging_equals_accumulating_together() {
        let passes = [[[1.0, 0.5, 0.0]], [[3.0, 1.5, 2.0]], [[0.0, 0.0, 4.0]]];
        let mut all = FilmSums::new(1, 1, 1, true);
        let (mut a, mut b) = (FilmSums::new(1, 1, 1, true), FilmSums::new(1, 1, 1, true));
        for (i, p) in passes.iter().enumerate() {
            all.add_pass(p);
            if i < 2 { &mut a } else { &mut b }.add_pass(p);
        }
        a.merge(&b).unwrap();
        assert_eq!(a, all);
        assert!(a.merge(&FilmSums::new(2, 1, 1, true)).is_err());
        assert!(a.merge(&FilmSums::new(1, 1, 4, true)).is_err());
    }

    #[test]
    fn relative_mse_is_zero_on_the_reference_and_guards_black() {
        let r = [[1.0, 0.0, 2.0]];
        assert_eq!(relative_mse(&r, &r), Some(0.0));
        let v = [[2.0, 0.1, 2.0]];
        let expected = (1.0 / 1.01 + 0.01 / 0.01) / 3.0;
        assert!((relative_mse(&v, &r).unwrap() - expected).abs() < 1e-6);
        assert_eq!(relative_mse(&v, &[]), None);
    }
}
