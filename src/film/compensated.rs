//! Film sums in two floats, as the GPU keeps them (`glsl/common/film_sum.glsl`, whose
//! twin this is).
//!
//! A GPU film of n pixels is 2n `vec4`: the n sums `hi`, then their n remainders `lo`;
//! a pixel's sum is hi + lo. One f32 would lose each sample's low bits to the sum's
//! rounding: 2^16 samples of 0.1 summed in f32 are off by 6e-4, 2^20 by 1%. Two floats
//! keep 48 significant bits.
//!
//! Each addition leaves the pair canonical: hi is the f32 nearest to hi + lo, lo the
//! exact rest, and lo a multiple of 2^(e − 48) where e is the binade of the sum before
//! the final TwoSum (frexp's exponent; at least −78, since ldexp's exponents stop at
//! −126). So hi + lo spans at most 49 bits: [`join`] is exact in an f64, and [`split`]
//! gives the pair back bit for bit — a film saved as f64 sums and restored continues
//! exactly as the uninterrupted one.

/// Knuth's TwoSum: `s = fl(a + b)` and `e` with `s + e = a + b` exactly.
fn two_sum(a: f32, b: f32) -> (f32, f32) {
    let s = a + b;
    let b_part = s - a;
    let a_part = s - b_part;
    (s, (a - a_part) + (b - b_part))
}

/// frexp's exponent: x = m 2^e with m in [0.5, 1) (0 for 0).
fn binade(x: f32) -> i32 {
    if x == 0.0 || !x.is_finite() {
        return 0;
    }
    // Subnormals are scaled into the normal range first.
    let (x, shift) = if x.abs() < f32::MIN_POSITIVE {
        (x * 2f32.powi(64), 64)
    } else {
        (x, 0)
    };
    ((x.to_bits() >> 23) & 0xff) as i32 - 126 - shift
}

/// x 2^n, exact where the result is an f32 (GLSL's `ldexp` for n in [−126, 128]).
fn ldexp(x: f32, n: i32) -> f32 {
    (x as f64 * 2f64.powi(n)) as f32
}

/// `film_add` of one lane: adds `x` to the pair (`hi`, `lo`).
fn add_lane(hi: &mut f32, lo: &mut f32, x: f32) {
    let (s, e) = two_sum(*hi, x);
    let rest = *lo + e;
    let b = binade(s).max(-78);
    let quantised = ldexp(ldexp(rest, 48 - b).round_ties_even(), b - 48);
    (*hi, *lo) = two_sum(s, quantised);
}

/// `film_add`: adds `x` to the pair (`hi`, `lo`), lane by lane.
pub fn add(hi: &mut [f32; 4], lo: &mut [f32; 4], x: [f32; 4]) {
    for c in 0..4 {
        add_lane(&mut hi[c], &mut lo[c], x[c]);
    }
}

/// Adds `x` to pixel `pixel` of a GPU film: `film[..n]` the n pixels' sums (xyz: RGB,
/// w: weight), `film[n..]` their remainders.
pub fn add_to_film(film: &mut [[f32; 4]], pixel: usize, x: [f32; 4]) {
    let (hi, lo) = film.split_at_mut(film.len() / 2);
    add(&mut hi[pixel], &mut lo[pixel], x);
}

/// The pair's value: exact for canonical pairs.
pub fn join(hi: f32, lo: f32) -> f64 {
    hi as f64 + lo as f64
}

/// The pair of `v`: the f32 nearest to it and the rest (rounded to f32). The inverse of
/// [`join`] on canonical pairs.
pub fn split(v: f64) -> (f32, f32) {
    let hi = v as f32;
    (hi, (v - hi as f64) as f32)
}

/// The pixels' sums (rgb of hi + lo, times `by`) of a GPU film of sums and remainders.
pub fn film_rgb(film: &[[f32; 4]], by: f64) -> Vec<[f64; 3]> {
    let (hi, lo) = film.split_at(film.len() / 2);
    hi.iter()
        .zip(lo)
        .map(|(h, l)| std::array::from_fn(|c| join(h[c], l[c]) * by))
        .collect()
}

/// A GPU film of sums and remainders holding `sums` (times `by`) with weight `w`.
pub fn film_of(sums: &[[f64; 3]], by: f64, w: f64) -> Vec<[f32; 4]> {
    let n = sums.len();
    let mut film = vec![[0.0; 4]; 2 * n];
    let (hi, lo) = film.split_at_mut(n);
    for ((h, l), s) in hi.iter_mut().zip(lo).zip(sums) {
        for c in 0..3 {
            (h[c], l[c]) = split(s[c] * by);
        }
        (h[3], l[3]) = split(w);
    }
    film
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sums `x` `n` times into a pair.
    fn repeated(x: f32, n: u32) -> (f32, f32) {
        let (mut hi, mut lo) = (0.0, 0.0);
        for _ in 0..n {
            add_lane(&mut hi, &mut lo, x);
        }
        (hi, lo)
    }

    #[test]
    fn a_million_samples_of_a_tenth_keep_their_sum() {
        let n = 1 << 20;
        let (hi, lo) = repeated(0.1, n);
        let exact = 0.1f32 as f64 * n as f64;
        // A plain f32 sum is 1% off here; the pair within 2^-47.
        assert!(
            (join(hi, lo) - exact).abs() <= exact * 2f64.powi(-47),
            "{hi} + {lo}"
        );
        let plain = (0..n).fold(0.0f32, |s, _| s + 0.1);
        assert!((plain as f64 - exact).abs() > exact * 1e-3);
    }

    #[test]
    fn pairs_are_canonical_and_round_trip_through_f64() {
        // Samples over 60 binades, a few adversarial ones among them.
        let mut state = 0x2545_f491u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state
        };
        let specials = [0.0, 1e-30, 3.0e-39, 1.0, 16_777_215.0, 0.1, 1e19];
        let (mut hi, mut lo) = (0.0f32, 0.0f32);
        for k in 0..200_000 {
            let x = match k % 50 {
                0..7 => specials[k % 50],
                _ => f32::from_bits((next() % 60 + 97) << 23 | (next() & 0x7f_ffff)),
            };
            add_lane(&mut hi, &mut lo, x);
            assert_eq!(hi, (hi as f64 + lo as f64) as f32, "hi nearest at {k}");
            assert_eq!(split(join(hi, lo)), (hi, lo), "round trip at {k}");
        }
    }

    #[test]
    fn tiny_sums_stay_plain_f32_sums() {
        let (hi, lo) = repeated(1e-35, 1000);
        assert_eq!(lo, 0.0);
        assert_eq!(split(join(hi, lo)), (hi, lo));
    }

    #[test]
    fn films_convert_both_ways() {
        let sums = [[0.1, 1e30, 3.0], [7.0, 0.0, 1.0 / 3.0]];
        let film = film_of(&sums, 1.0, (1u64 << 30) as f64 + 1.0);
        assert_eq!(film.len(), 4);
        assert_eq!(
            film[0][3] as f64 + film[2][3] as f64,
            (1u64 << 30) as f64 + 1.0
        );
        let back = film_rgb(&film, 1.0);
        for (b, s) in back.iter().zip(&sums) {
            for c in 0..3 {
                assert!((b[c] - s[c]).abs() <= s[c].abs() * 2f64.powi(-47));
            }
        }
        assert_eq!(film_rgb(&film_of(&back, 1.0, 0.0), 1.0), back);
    }
}
