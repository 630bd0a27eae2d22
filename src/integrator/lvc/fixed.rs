//! Deterministic film sums: the CPU twin of `glsl/integrator/lvc/lvc_fixed.glsl`.
//!
//! Light tracing splats land on any pixel from any invocation. Added as floats with
//! atomics, a pixel's sum would depend on the order of the additions, so the image would
//! change from run to run. Instead each non-negative value is cut into a Q32.32 fixed-point
//! number (32 integer bits, 32 fractional bits) and added as two 32-bit integer atomics
//! (low word, then the carry and the high word): integer addition is associative and
//! commutative, so the 64-bit sum is exact and the same in any order.
//!
//! The range is 2^-32 ≈ 2.3e-10 to 2^31: each part is rounded to the nearest 2^-32 (ties
//! to even, so that rounding errors cancel on average rather than all cutting the sum
//! down), and parts above [`FIXED_MAX`] are clamped and counted. Scenes come in any
//! units, so values are first multiplied by a power of two that puts the scene's
//! brightest emitter near 1 ([`LightTable::brightness_scale`]), and divided by it when
//! the film is read: multiplying by a power of two is exact, and splats then sit in the
//! middle of the range whether the lights emit 1e-8 or 1e8.
//!
//! [`LightTable::brightness_scale`]: crate::integrator::pt::LightTable::brightness_scale

/// Words per slot: the low words of r, g, b, then their high words.
pub const FIXED_WORDS: usize = 6;
/// The largest part (the largest f32 below 2^31).
pub const FIXED_MAX: f32 = 2_147_483_520.0;
const FIXED_ONE: f32 = 4_294_967_296.0;

/// The (low, high) words of a part, as `fixed_add_channel` computes them (`None` for a
/// value that adds nothing: zero, negative or NaN). The flag says it was clamped.
pub fn parts(v: f32) -> Option<(u32, u32, bool)> {
    if !crate::bidir::positive(v) {
        return None;
    }
    let clamped = v > FIXED_MAX;
    let v = v.min(FIXED_MAX);
    let whole = v.floor();
    let fraction = ((v - whole) * FIXED_ONE).round_ties_even();
    Some((fraction as u32, whole as u32, clamped))
}

/// A film of fixed-point RGB sums, summed on the CPU.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedFilm {
    /// Per slot and channel: the 64-bit sum (wrapping, as the GPU's words).
    pub sums: Vec<[u64; 3]>,
    pub clamped: u64,
    /// What values are multiplied by before they are added (the brightness scale).
    pub scale: f32,
}

impl FixedFilm {
    pub fn new(slots: usize, scale: f32) -> Self {
        Self {
            sums: vec![[0; 3]; slots],
            clamped: 0,
            scale,
        }
    }

    /// Adds a non-negative RGB value to `slot`, scaled (`fixed_add` of `splat.comp`).
    pub fn add(&mut self, slot: usize, v: [f32; 3]) {
        for (c, &x) in v.iter().enumerate() {
            if let Some((lo, hi, clamped)) = parts(x * self.scale) {
                let part = ((hi as u64) << 32) | lo as u64;
                self.sums[slot][c] = self.sums[slot][c].wrapping_add(part);
                self.clamped += clamped as u64;
            }
        }
    }

    /// The GPU's words (six per slot), added at `scale`, as 64-bit sums.
    pub fn from_words(words: &[u32], scale: f32) -> Self {
        let sums = words
            .chunks_exact(FIXED_WORDS)
            .map(|w| std::array::from_fn(|c| ((w[3 + c] as u64) << 32) | w[c] as u64))
            .collect();
        Self {
            sums,
            clamped: 0,
            scale,
        }
    }

    /// The value of a slot, unscaled, as `finish.comp` reads it.
    pub fn value(&self, slot: usize) -> [f32; 3] {
        self.sums[slot].map(|s| {
            let fixed = ((s >> 32) as u32) as f32 + ((s & 0xFFFF_FFFF) as u32) as f32 / FIXED_ONE;
            fixed * (1.0 / self.scale)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_split_exactly_and_sums_are_order_free() {
        assert_eq!(parts(0.0), None);
        assert_eq!(parts(-1.0), None);
        assert_eq!(parts(f32::NAN), None);
        assert_eq!(parts(1.5), Some((1 << 31, 1, false)));
        assert_eq!(parts(0.25), Some((1 << 30, 0, false)));
        assert_eq!(parts(1e12), Some((0, FIXED_MAX as u32, true)));
        // Rounded to the nearest 2^-32, ties to even.
        assert_eq!(parts(2f32.powi(-33)), Some((0, 0, false)));
        assert_eq!(parts(3.0 * 2f32.powi(-33)), Some((2, 0, false)));
        assert_eq!(parts(0.7 * 2f32.powi(-32)), Some((1, 0, false)));
        // Sums of many parts in two orders, with carries out of the low words.
        let values: Vec<f32> = (0..1000).map(|i| 0.37 + (i as f32) * 0.731).collect();
        let (mut a, mut b) = (FixedFilm::new(1, 1.0), FixedFilm::new(1, 1.0));
        for &v in &values {
            a.add(0, [v, v * 0.5, 0.999_999_9]);
        }
        for &v in values.iter().rev() {
            b.add(0, [v, v * 0.5, 0.999_999_9]);
        }
        assert_eq!(a, b);
        let exact: f64 = values.iter().map(|&v| v as f64).sum();
        assert!((a.value(0)[0] as f64 - exact).abs() < 1e-6 * exact);
    }
}
