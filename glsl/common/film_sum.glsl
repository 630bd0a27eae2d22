// Film sums in two floats. A film of n pixels on the GPU is 2n vec4: the n sums `hi`,
// then their n remainders `lo`; a sum is hi + lo. One f32 would lose a sample's low bits
// to the sum's rounding: after 2^16 samples of 0.1 a plain f32 sum is off by 6e-4, after
// 2^20 by 1%. Two floats keep 48 significant bits.
//
// The pair is kept canonical, so that it converts to one f64 and back without changing
// a bit (FilmSums::from_gpu and to_gpu: checkpoints resume bit-identical):
// - hi is the f32 nearest to hi + lo and lo the exact rest (a final TwoSum);
// - lo is a multiple of 2^(e - 48), e the binade of the sum before that TwoSum
//   (s = m 2^e, m in [0.5, 1)), so that hi + lo spans at most 49 bits and is exact in
//   an f64. Below
//   2^-79 the multiple is of 2^-126 (ldexp's exponents stop at -126), which keeps pairs
//   within 49 bits too; below 2^-103 it rounds lo away, leaving plain f32 sums.
// Twin: src/film/compensated.rs (`add`). `precise` keeps compilers from fusing or
// reordering the additions, which would lose the very rounding errors this keeps.
#ifndef FILM_SUM_GLSL
#define FILM_SUM_GLSL

// Knuth's TwoSum: s = fl(a + b) and e such that s + e = a + b exactly.
void film_two_sum(vec4 a, vec4 b, out vec4 s, out vec4 e) {
    precise vec4 sum = a + b;
    precise vec4 b_part = sum - a;
    precise vec4 a_part = sum - b_part;
    precise vec4 err = (a - a_part) + (b - b_part);
    s = sum;
    e = err;
}

// Adds x to the pair (hi, lo).
void film_add(inout vec4 hi, inout vec4 lo, vec4 x) {
    vec4 s, e;
    film_two_sum(hi, x, s, e);
    precise vec4 rest = lo + e;
    // The rest to a multiple of 2^-48 of s's binade (ldexp and roundEven are exact).
    ivec4 binade;
    frexp(s, binade);
    binade = max(binade, ivec4(-78));
    precise vec4 quantised = ldexp(roundEven(ldexp(rest, 48 - binade)), binade - 48);
    film_two_sum(s, quantised, hi, lo);
}

// Adds x to pixel `pixel` of `film` (an array expression: `accum`, `accum.data`), a film
// of `pixels` pixels: its sum at `pixel`, its remainder at `pixel + pixels`.
#define FILM_ADD(film, pixel, pixels, x)                    \
    {                                                       \
        uint film_rest_ = (pixel) + (pixels);               \
        vec4 film_hi_ = film[pixel];                        \
        vec4 film_lo_ = film[film_rest_];                   \
        film_add(film_hi_, film_lo_, x);                    \
        film[pixel] = film_hi_;                             \
        film[film_rest_] = film_lo_;                        \
    }

#endif
