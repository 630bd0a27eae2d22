//! References: converged images that a render's error is measured against.
//!
//! A reference is itself a Monte Carlo estimate, r = μ + e, with a standard error se per
//! pixel and channel. For a film v rendered independently of it,
//! E[(v − r)²] = E[(v − μ)²] + se², so the relative MSE against r (the mean over pixels
//! and channels of (v − r)² / (r² + ε), [`relative_mse`]) overstates the film's own error
//! by the reference's noise, (1/n) Σ se² / (r² + ε) ([`Reference::own_relative_mse`]).
//! Once two films' errors come near that floor, the ratio of their raw relative MSEs
//! tends to 1 whatever their own errors are: [`Reference::error`] subtracts the floor
//! where the reference's standard errors are known, an unbiased estimate of the error
//! against μ (up to the noise of r in the denominator, second order in se / r).
//!
//! The standard errors come from the reference file: the `stderr.R/G/B` channels that
//! splitray's own renders write, or, for a `NAME_mean.exr` without them, the RGB of
//! `NAME_stderr.exr` beside it (the form of `tools/mitsuba_reference.py`'s references).

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::sums::relative_channel_mean;
use super::{read_exr, relative_mse, FilmError};

/// A reference image: its mean RGB and, where known, each pixel's standard error.
#[derive(Clone, Debug)]
pub struct Reference {
    pub mean: Vec<[f32; 3]>,
    pub stderr: Option<Vec<[f32; 3]>>,
    /// The file the mean came from.
    pub path: PathBuf,
    /// The file the standard errors came from (the same one, or `NAME_stderr.exr`).
    pub stderr_path: Option<PathBuf>,
}

/// A film's error against a [`Reference`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReferenceError {
    /// Relative MSE against the reference as it is.
    pub relative_mse: f64,
    /// `relative_mse` less the reference's own noise: the film's estimated error against
    /// the reference's expectation (may come out ≤ 0 for a film whose error is below
    /// the reference's noise). `None` where the reference has no standard errors.
    pub excess: Option<f64>,
}

impl ReferenceError {
    /// The error two films are compared by: the excess where the reference's noise is
    /// known and the excess is positive, the raw relative MSE where the noise is
    /// unknown, `None` where the film's error is inside the reference's noise.
    pub fn comparable(&self) -> Option<f64> {
        match self.excess {
            Some(e) if e > 0.0 => Some(e),
            Some(_) => None,
            None => Some(self.relative_mse),
        }
    }
}

impl Reference {
    /// Reads a reference EXR (see the module docs for where its standard errors come
    /// from), refused unless it is `width × height`.
    pub fn read(path: &Path, width: u32, height: u32) -> Result<Self, FilmError> {
        let film = read_sized(path, width, height, "the reference is", "the film")?;
        let mean = film.mean_rgb_buffer();
        let (stderr, stderr_path) = match film.stderr {
            Some(se) => (Some(se), Some(path.to_path_buf())),
            None => match sibling_stderr(path).filter(|p| p.exists()) {
                Some(sibling) => (Some(read_sibling(&sibling, width, height)?), Some(sibling)),
                None => (None, None),
            },
        };
        if let Some(se) = &stderr {
            if let Some(bad) = se.iter().flatten().find(|s| !(s.is_finite() && **s >= 0.0)) {
                let file = stderr_path.as_deref().unwrap_or(path);
                return Err(FilmError::invalid(
                    file,
                    format!("a standard error of {bad}: they must be finite and not negative"),
                ));
            }
        }
        Ok(Self {
            mean,
            stderr,
            path: path.to_path_buf(),
            stderr_path,
        })
    }

    /// Its file, and the other file its standard errors came from, if any.
    pub fn describe(&self) -> String {
        match &self.stderr_path {
            Some(se) if *se != self.path => {
                format!(
                    "{} (standard errors: {})",
                    self.path.display(),
                    se.display()
                )
            }
            _ => self.path.display().to_string(),
        }
    }

    /// The relative MSE that the reference's own noise adds to any film's against it:
    /// (1/n) Σ se² / (r² + ε), as [`relative_mse`] weights it.
    pub fn own_relative_mse(&self) -> Option<f64> {
        let stderr = self.stderr.as_ref()?;
        Some(relative_channel_mean(stderr, &self.mean, |s, _| s * s))
    }

    /// `image`'s error against the reference; `None` when its size differs.
    pub fn error(&self, image: &[[f32; 3]]) -> Option<ReferenceError> {
        let raw = relative_mse(image, &self.mean)?;
        Some(ReferenceError {
            relative_mse: raw,
            excess: self.own_relative_mse().map(|noise| raw - noise),
        })
    }
}

/// `NAME_stderr.exr` beside `NAME_mean.exr`.
fn sibling_stderr(path: &Path) -> Option<PathBuf> {
    let name = path.file_name()?.to_str()?;
    let stem = name.strip_suffix("_mean.exr")?;
    Some(path.with_file_name(format!("{stem}_stderr.exr")))
}

/// A standard-error image: RGB of the reference's size.
fn read_sibling(path: &Path, width: u32, height: u32) -> Result<Vec<[f32; 3]>, FilmError> {
    let film = read_sized(
        path,
        width,
        height,
        "the standard errors are",
        "the reference",
    )?;
    Ok(film.mean_rgb_buffer())
}

/// The EXR at `path`, refused unless it is `width × height` ("`what` AxB, `other`
/// WxH").
fn read_sized(
    path: &Path,
    width: u32,
    height: u32,
    what: &str,
    other: &str,
) -> Result<super::Film, FilmError> {
    let (film, _) = read_exr(path)?;
    if (film.width(), film.height()) != (width, height) {
        return Err(FilmError::invalid(
            path,
            format!(
                "{what} {}x{}, {other} {width}x{height}",
                film.width(),
                film.height()
            ),
        ));
    }
    Ok(film)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference(mean: Vec<[f32; 3]>, stderr: Option<Vec<[f32; 3]>>) -> Reference {
        Reference {
            mean,
            stderr,
            path: PathBuf::from("ref.exr"),
            stderr_path: None,
        }
    }

    #[test]
    fn own_noise_weights_like_relative_mse() {
        let r = reference(
            vec![[1.0, 0.0, 2.0], [0.5, 0.5, 0.5]],
            Some(vec![[0.1, 0.1, 0.2], [0.0, 0.05, 0.0]]),
        );
        let want = (0.01 / 1.01 + 0.01 / 0.01 + 0.04 / 4.01 + 0.0 + 0.0025 / 0.26 + 0.0) / 6.0;
        let got = r.own_relative_mse().unwrap();
        // The inputs are f32: their rounding, not the sum, bounds the agreement.
        assert!((got - want).abs() < 1e-6 * want, "{got} against {want}");
        assert_eq!(reference(vec![[1.0; 3]], None).own_relative_mse(), None);
    }

    #[test]
    fn error_subtracts_the_reference_noise() {
        let r = reference(vec![[1.0; 3]; 2], Some(vec![[0.1; 3]; 2]));
        let noise = 0.01 / 1.01;
        let e = r.error(&[[1.2; 3], [0.8; 3]]).unwrap();
        assert!((e.relative_mse - 0.04 / 1.01).abs() < 1e-7);
        assert!((e.excess.unwrap() - (0.04 / 1.01 - noise)).abs() < 1e-7);
        assert_eq!(e.comparable(), e.excess);
        // Below the reference's noise: nothing to compare.
        let close = r.error(&[[1.01; 3]; 2]).unwrap();
        assert!(close.excess.unwrap() < 0.0);
        assert_eq!(close.comparable(), None);
        // Without standard errors: the raw figure.
        let plain = reference(vec![[1.0; 3]; 2], None)
            .error(&[[1.2; 3]; 2])
            .unwrap();
        assert_eq!(plain.excess, None);
        assert_eq!(plain.comparable(), Some(plain.relative_mse));
        assert_eq!(r.error(&[[1.0; 3]]), None);
    }

    /// A noisy reference of known standard errors and a film of known error, both
    /// around the same truth: the excess estimates the film's error against the truth
    /// within its standard error; the raw figure is off by the reference's noise.
    #[test]
    fn excess_estimates_the_error_against_the_expectation() {
        use crate::bidir::random::random01;
        let n = 64 * 64;
        let u = |i: usize, dim: u32| random01(i as u32, 0, dim, 7);
        // Uniform noise of half-width a: variance a² / 3.
        let noise = |i: usize, dim: u32, a: f32| a * (2.0 * u(i, dim) - 1.0);
        let truth: Vec<[f32; 3]> = (0..n)
            .map(|i| {
                [
                    0.2 + 0.8 * u(i, 0),
                    0.05 + 0.5 * u(i, 1),
                    1.0 + 2.0 * u(i, 2),
                ]
            })
            .collect();
        // Reference: ±6 % of the truth; film: ±4 %, below the reference's noise.
        let (a_ref, a_film) = (0.06, 0.04);
        let mean: Vec<[f32; 3]> = (0..n)
            .map(|i| {
                std::array::from_fn(|c| truth[i][c] + noise(i, 3 + c as u32, a_ref * truth[i][c]))
            })
            .collect();
        let stderr: Vec<[f32; 3]> = truth
            .iter()
            .map(|t| t.map(|v| a_ref * v / 3f32.sqrt()))
            .collect();
        let film: Vec<[f32; 3]> = (0..n)
            .map(|i| {
                std::array::from_fn(|c| truth[i][c] + noise(i, 6 + c as u32, a_film * truth[i][c]))
            })
            .collect();
        let r = Reference {
            mean: mean.clone(),
            stderr: Some(stderr),
            path: PathBuf::from("ref.exr"),
            stderr_path: None,
        };
        // What the excess estimates: the film's expected squared error, weighted as the
        // relative MSE weights it (by the reference's values).
        let weights = || {
            mean.iter()
                .flat_map(|m| m.map(|r| 1.0 / (r as f64 * r as f64 + 0.01)))
        };
        let film_variance = truth
            .iter()
            .flat_map(|t| t.map(|v| (a_film as f64 * v as f64).powi(2) / 3.0));
        let target = film_variance
            .zip(weights())
            .map(|(v, w)| v * w)
            .sum::<f64>()
            / (3 * n) as f64;
        // The standard error of the raw figure, from the spread of its terms.
        let terms: Vec<f64> = film
            .iter()
            .zip(&mean)
            .flat_map(|(v, m)| (0..3).map(move |c| (v[c] as f64 - m[c] as f64).powi(2)))
            .zip(weights())
            .map(|(d, w)| d * w)
            .collect();
        let average = terms.iter().sum::<f64>() / terms.len() as f64;
        let spread =
            terms.iter().map(|t| (t - average).powi(2)).sum::<f64>() / (terms.len() - 1) as f64;
        let se = (spread / terms.len() as f64).sqrt();
        let e = r.error(&film).unwrap();
        let excess = e.excess.unwrap();
        assert!(
            (excess - target).abs() < 4.0 * se,
            "excess {excess:.4e} against the film's {target:.4e} (standard error {se:.2e})"
        );
        assert!(
            e.relative_mse - target > 20.0 * se,
            "the raw {:.4e} should carry the reference's noise above {target:.4e}",
            e.relative_mse
        );
    }

    #[test]
    fn finds_the_stderr_file_of_a_mean_file() {
        assert_eq!(
            sibling_stderr(Path::new("a/b/fixture_ptracer_64_mean.exr")),
            Some(PathBuf::from("a/b/fixture_ptracer_64_stderr.exr"))
        );
        assert_eq!(sibling_stderr(Path::new("a/lamps_ref_64.exr")), None);
    }
}
