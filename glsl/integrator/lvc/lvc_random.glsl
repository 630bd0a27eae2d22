// Cache-vertex selection: exactly uniform integers from the counter-based hash of
// random.glsl (src/integrator/lvc/twin.rs `uniform_index` is the CPU twin of
// uniform_index_below).
#ifndef SPLITRAY_LVC_RANDOM_GLSL
#define SPLITRAY_LVC_RANDOM_GLSL

#include "random.glsl"

// The full 32-bit hash whose top 24 bits random01 returns.
uint random_u32(uint index, uint sample_index, uint dimension, uint seed) {
    return pcg_hash(index ^ pcg_hash(sample_index ^ pcg_hash(dimension ^ pcg_hash(seed))));
}

// Tries of uniform_index before it takes a biased draw (each rejected with probability
// below size / 2^32: never, in practice).
const uint UNIFORM_TRIES = 8u;
// Dimension offset between two tries.
const uint UNIFORM_RETRY_STRIDE = 0x01000000u;

// The low products uniform_index rejects for `size` are those below this: 2^32 mod size.
// An integer division, which lavapipe does lane by lane: callers drawing several indices
// in one range compute it once.
uint uniform_threshold(uint size) { return (0u - size) % size; }

// An index in [0, size), size > 0, exactly uniform: Lemire's multiply-shift, rejecting
// the low products that would favour some indices (a float u * size is not uniform once
// size nears 2^24). Each retry hashes another dimension, so the result stays a pure
// function of (index, sample, dimension, seed). `threshold`: uniform_threshold(size).
uint uniform_index_below(uint index, uint sample_index, uint dimension, uint seed, uint size,
                         uint threshold) {
    uint hi = 0u;
    for (uint k = 0u; k < UNIFORM_TRIES; ++k) {
        uint h = random_u32(index, sample_index, dimension + k * UNIFORM_RETRY_STRIDE, seed);
        uint lo;
        umulExtended(h, size, hi, lo);
        if (lo >= threshold) return hi;
    }
    return hi;
}

#endif
