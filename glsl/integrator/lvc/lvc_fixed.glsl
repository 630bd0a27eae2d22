// Deterministic film sums: non-negative values added as Q32.32 fixed point with 32-bit
// integer atomics, so that the sums do not depend on the order of the additions (float
// atomics would). Each slot is six words: the low words of r, g, b, then the high words.
// A carry out of a low word goes to its high word; integer addition is associative, so
// the final 64-bit value is exactly the sum of the parts, however the atomics interleave.
// Each part is rounded to the nearest multiple of 2^-32 (ties to even), so that the sum's
// rounding errors cancel on average instead of all cutting it down. Callers scale
// values by a power of two that puts the scene's radiance near 1 (LvcConstants'
// brightness_scale), which keeps splats well inside the 2^-32 .. 2^31 range whatever
// the scene's units. Needs the uint buffer `fixed_film`; kernels that add define
// LVC_FIXED_ADD and also declare the uint buffer `counters` (each a BUFFER_REF or
// BUFFER_BINDING of address.glsl). src/integrator/lvc/fixed.rs is the twin.
#ifndef SPLITRAY_LVC_FIXED_GLSL
#define SPLITRAY_LVC_FIXED_GLSL

const uint FIXED_WORDS = 6u;
// The largest value a part may have (the largest float below 2^31): larger values are
// clamped to it and counted, so that a sum of 2^32 parts cannot wrap around.
const float FIXED_MAX = 2147483520.0;
const float FIXED_ONE = 4294967296.0;
const uint COUNTER_NON_FINITE = 0u;
const uint COUNTER_CLAMPED = 1u;

#ifdef LVC_FIXED_ADD
void fixed_add_channel(uint base, uint channel, float v) {
    if (!(v > 0.0)) return;
    if (v > FIXED_MAX) {
        v = FIXED_MAX;
        atomicAdd(counters.data[COUNTER_CLAMPED], 1u);
    }
    float whole = floor(v);
    uint hi = uint(whole);
    // (v - whole) < 1, so the rounded fraction stays below 2^32 (at most 2^32 - 2^8).
    uint lo = uint(roundEven((v - whole) * FIXED_ONE));
    uint old = atomicAdd(fixed_film.data[base + channel], lo);
    if (old > 0xFFFFFFFFu - lo) hi += 1u;
    if (hi != 0u) atomicAdd(fixed_film.data[base + 3u + channel], hi);
}

void fixed_add(uint slot, vec3 v) {
    uint base = slot * FIXED_WORDS;
    fixed_add_channel(base, 0u, v.r);
    fixed_add_channel(base, 1u, v.g);
    fixed_add_channel(base, 2u, v.b);
}
#endif

vec3 fixed_value(uint slot) {
    uint base = slot * FIXED_WORDS;
    vec3 v;
    for (uint c = 0u; c < 3u; ++c) {
        v[c] = float(fixed_film.data[base + 3u + c]) + float(fixed_film.data[base + c]) * (1.0 / FIXED_ONE);
    }
    return v;
}

#endif
