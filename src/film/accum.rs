//! [`Film`]: linear HDR accumulation of radiance estimates plus optional AOVs.

use super::FilmError;

/// A linear-HDR image being accumulated, plus optional arbitrary-output-variables (AOVs).
///
/// # Layout
/// Pixels are stored row-major, row 0 is the **top** of the image, and
/// `pixel_index = y * width + x` — the same layout the GPU kernels write and
/// the same layout EXR uses.
///
/// # Weights
/// The estimate of a pixel is `sum_i w_i * L_i / sum_i w_i`. The total weight of a
/// pixel is the number of whole-film passes ([`Film::spp`], one sample of weight 1
/// per pixel, added with [`Film::accumulate`]) plus an optional per-pixel weight
/// (samples added one by one with [`Film::add_sample_rgb`] /
/// [`Film::add_weighted_sample_rgb`]). The per-pixel weight buffer is only allocated
/// once a per-pixel sample is added, so the common case (whole passes) costs nothing
/// extra. Sums are kept in `f64` so that long renders do not lose precision.
///
/// # AOVs
/// The AOV fields are plain `Option<Vec<_>>` with one element per pixel; they are not
/// averaged (the renderer decides what to store, usually the primary hit of the first
/// pass). Their lengths are checked by the `set_*` helpers and again by the writers.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    /// Weighted radiance sums.
    sum: Vec<[f64; 3]>,
    /// Whole-film passes of one sample (weight 1) per pixel.
    passes: u32,
    /// Extra per-pixel weight from individually added samples.
    pixel_weight: Option<Vec<f64>>,
    /// Hit distance along the **unit** ray direction; `f32::INFINITY` for a miss.
    pub depth: Option<Vec<f32>>,
    /// Index of the hit triangle in the scene; `u32::MAX` ([`Film::NO_TRIANGLE`]) for a miss.
    pub triangle_id: Option<Vec<u32>>,
    /// Shading (or geometric — the renderer decides) normal at the hit; zero for a miss.
    pub normal: Option<Vec<[f32; 3]>>,
    /// Standard error of each pixel's estimate (RGB), where the integrator kept second
    /// moments and rendered two passes or more; what merging shards needs besides the mean.
    pub stderr: Option<Vec<[f32; 3]>>,
}

impl Film {
    /// The `triangle_id` of a pixel whose primary ray missed.
    pub const NO_TRIANGLE: u32 = u32::MAX;

    /// An empty (all-zero, zero-weight) film of `width` x `height` pixels, without AOVs.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            sum: vec![[0.0; 3]; n],
            passes: 0,
            pixel_weight: None,
            depth: None,
            triangle_id: None,
            normal: None,
            stderr: None,
        }
    }

    /// A film whose estimate is exactly `rgb` (one pass of weight 1), e.g. an image read
    /// back from disk. [`Film::mean_rgb`] then returns the given values bit-exactly.
    pub fn from_mean_rgb(width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<Self, FilmError> {
        let mut film = Self::new(width, height);
        film.check_len("mean RGB buffer", rgb.len())?;
        for (s, c) in film.sum.iter_mut().zip(rgb) {
            *s = c.map(f64::from);
        }
        film.passes = 1;
        Ok(film)
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// `width * height`.
    pub fn pixel_count(&self) -> usize {
        self.sum.len()
    }

    /// `y * width + x`. Panics if `(x, y)` is outside the film.
    pub fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside {}x{} film",
            self.width,
            self.height
        );
        y as usize * self.width as usize + x as usize
    }

    /// Number of whole-film passes accumulated with [`Film::accumulate`].
    pub fn spp(&self) -> u32 {
        self.passes
    }

    /// Adds one whole-film pass: one sample of weight 1 for every pixel.
    ///
    /// `pass` is the GPU's per-pixel `vec4` buffer (`.xyz` = RGB radiance, `.w` ignored),
    /// `pass.len()` must be `width * height`. Non-finite values are accumulated as-is
    /// (they are counted and reported when the film is written).
    pub fn accumulate(&mut self, pass: &[[f32; 4]]) -> Result<(), FilmError> {
        self.check_len("pass buffer", pass.len())?;
        for (s, p) in self.sum.iter_mut().zip(pass) {
            s[0] += f64::from(p[0]);
            s[1] += f64::from(p[1]);
            s[2] += f64::from(p[2]);
        }
        self.passes += 1;
        Ok(())
    }

    /// Adds one sample of weight 1 to pixel `pixel_index`. Panics if the index is out of range.
    pub fn add_sample_rgb(&mut self, pixel_index: usize, rgb: [f32; 3]) {
        self.add_weighted_sample_rgb(pixel_index, rgb, 1.0);
    }

    /// Adds `weight * rgb` to the pixel's sum and `weight` to its total weight (a
    /// filter-weighted or otherwise weighted sample). Panics if the index is out of range.
    pub fn add_weighted_sample_rgb(&mut self, pixel_index: usize, rgb: [f32; 3], weight: f32) {
        let n = self.sum.len();
        let w = f64::from(weight);
        let s = &mut self.sum[pixel_index];
        for (s, c) in s.iter_mut().zip(rgb) {
            *s += w * f64::from(c);
        }
        self.pixel_weight.get_or_insert_with(|| vec![0.0; n])[pixel_index] += w;
    }

    /// Total sample weight of a pixel (passes plus per-pixel weight).
    pub fn weight(&self, pixel_index: usize) -> f64 {
        let extra = self.pixel_weight.as_ref().map_or(0.0, |w| w[pixel_index]);
        f64::from(self.passes) + extra
    }

    /// The current estimate of a pixel: weighted mean of its samples, `[0; 3]` when the
    /// pixel has no weight yet.
    pub fn mean_rgb(&self, pixel_index: usize) -> [f32; 3] {
        let w = self.weight(pixel_index);
        if w == 0.0 {
            return [0.0; 3];
        }
        self.sum[pixel_index].map(|s| (s / w) as f32)
    }

    /// [`Film::mean_rgb`] of every pixel, in pixel-index order.
    pub fn mean_rgb_buffer(&self) -> Vec<[f32; 3]> {
        (0..self.pixel_count()).map(|i| self.mean_rgb(i)).collect()
    }

    /// Number of pixels whose estimate has a NaN or infinite component.
    pub fn count_non_finite(&self) -> usize {
        (0..self.pixel_count())
            .filter(|&i| self.mean_rgb(i).iter().any(|c| !c.is_finite()))
            .count()
    }

    /// Resets the radiance accumulation (sums, passes, per-pixel weights); keeps the AOVs.
    pub fn clear(&mut self) {
        self.sum.iter_mut().for_each(|s| *s = [0.0; 3]);
        self.passes = 0;
        self.pixel_weight = None;
    }

    /// Sets the depth AOV (hit distance along the unit ray direction, `+inf` on a miss).
    pub fn set_depth(&mut self, depth: Vec<f32>) -> Result<(), FilmError> {
        self.check_len("depth AOV", depth.len())?;
        self.depth = Some(depth);
        Ok(())
    }

    /// Sets the triangle-id AOV (`u32::MAX` on a miss).
    pub fn set_triangle_id(&mut self, ids: Vec<u32>) -> Result<(), FilmError> {
        self.check_len("triangle_id AOV", ids.len())?;
        self.triangle_id = Some(ids);
        Ok(())
    }

    /// Sets the normal AOV.
    pub fn set_normal(&mut self, normals: Vec<[f32; 3]>) -> Result<(), FilmError> {
        self.check_len("normal AOV", normals.len())?;
        self.normal = Some(normals);
        Ok(())
    }

    /// Sets the standard error of each pixel's estimate.
    pub fn set_stderr(&mut self, stderr: Vec<[f32; 3]>) -> Result<(), FilmError> {
        self.check_len("standard error", stderr.len())?;
        self.stderr = Some(stderr);
        Ok(())
    }

    /// Refuses to write a film with no pixels to `path` (an image file needs one).
    pub(crate) fn refuse_empty(&self, path: &std::path::Path) -> Result<(), FilmError> {
        if self.pixel_count() == 0 {
            return Err(FilmError::invalid(
                path,
                format!(
                    "cannot write an empty {}x{} film",
                    self.width(),
                    self.height()
                ),
            ));
        }
        Ok(())
    }

    /// Checks that every present AOV has one element per pixel.
    pub fn validate_aovs(&self) -> Result<(), FilmError> {
        if let Some(s) = &self.stderr {
            self.check_len("standard error", s.len())?;
        }
        if let Some(d) = &self.depth {
            self.check_len("depth AOV", d.len())?;
        }
        if let Some(t) = &self.triangle_id {
            self.check_len("triangle_id AOV", t.len())?;
        }
        if let Some(n) = &self.normal {
            self.check_len("normal AOV", n.len())?;
        }
        Ok(())
    }

    fn check_len(&self, what: &'static str, got: usize) -> Result<(), FilmError> {
        let expected = self.width as usize * self.height as usize;
        if got == expected {
            Ok(())
        } else {
            Err(FilmError::SizeMismatch {
                what,
                got,
                expected,
                width: self.width,
                height: self.height,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_average() {
        let mut f = Film::new(2, 1);
        f.accumulate(&[[1.0, 2.0, 3.0, 9.0], [0.0; 4]]).unwrap();
        f.accumulate(&[[3.0, 4.0, 5.0, 9.0], [1.0; 4]]).unwrap();
        assert_eq!(f.spp(), 2);
        assert_eq!(f.mean_rgb(0), [2.0, 3.0, 4.0]);
        assert_eq!(f.mean_rgb(1), [0.5, 0.5, 0.5]);
        assert_eq!(f.weight(1), 2.0);
    }

    #[test]
    fn wrong_pass_size_is_an_error() {
        let mut f = Film::new(3, 2);
        let e = f.accumulate(&[[0.0; 4]; 5]).unwrap_err();
        assert!(matches!(
            e,
            FilmError::SizeMismatch {
                got: 5,
                expected: 6,
                ..
            }
        ));
        assert_eq!(f.spp(), 0);
        assert!(f.set_depth(vec![0.0; 7]).is_err());
        assert!(f.depth.is_none());
    }

    #[test]
    fn per_pixel_and_weighted_samples_mix_with_passes() {
        let mut f = Film::new(2, 2);
        assert_eq!(f.mean_rgb(3), [0.0; 3], "zero weight gives black");
        f.accumulate(&[[1.0, 1.0, 1.0, 0.0]; 4]).unwrap();
        f.add_sample_rgb(3, [4.0, 4.0, 4.0]);
        assert_eq!(f.mean_rgb(3), [2.5; 3]);
        assert_eq!(f.mean_rgb(0), [1.0; 3]);
        f.add_weighted_sample_rgb(0, [10.0, 0.0, 4.0], 3.0);
        // (1 + 30) / 4, (1 + 0) / 4, (1 + 12) / 4
        assert_eq!(f.mean_rgb(0), [7.75, 0.25, 3.25]);
        assert_eq!(f.weight(0), 4.0);
    }

    #[test]
    fn many_passes_keep_precision() {
        let mut f = Film::new(1, 1);
        for i in 0..100_000 {
            let v = if i % 2 == 0 { 0.1 } else { 0.3 };
            f.accumulate(&[[v, v, v, 0.0]]).unwrap();
        }
        let m = f.mean_rgb(0)[0];
        assert!((m - 0.2).abs() < 1e-6, "{m}");
    }

    #[test]
    fn from_mean_is_bit_exact_and_counts_non_finite() {
        let px = [
            [0.1, -3.5e-20, 1e30],
            [f32::NAN, 0.0, 1.0],
            [f32::INFINITY, 0.0, 0.0],
        ];
        let f = Film::from_mean_rgb(3, 1, &px).unwrap();
        assert_eq!(f.mean_rgb(0).map(f32::to_bits), px[0].map(f32::to_bits));
        assert_eq!(f.count_non_finite(), 2);
    }

    #[test]
    fn clear_resets_accumulation() {
        let mut f = Film::new(1, 1);
        f.accumulate(&[[1.0; 4]]).unwrap();
        f.add_sample_rgb(0, [1.0; 3]);
        f.clear();
        assert_eq!(f.spp(), 0);
        assert_eq!(f.weight(0), 0.0);
        assert_eq!(f.mean_rgb(0), [0.0; 3]);
        assert_eq!(f.index(0, 0), 0);
    }
}
