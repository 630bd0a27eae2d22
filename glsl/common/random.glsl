// Counter-based random numbers: a value is a pure function of (pixel, sample, dimension,
// seed), so images do not depend on scheduling, chunking or device.
// Mirrored by src/bidir/random.rs (tests/suite/bidir_random.rs compares the two).
#ifndef SPLITRAY_RANDOM_GLSL
#define SPLITRAY_RANDOM_GLSL

// PCG-style 32-bit hash (Jarzynski & Olano, "Hash Functions for GPU Rendering", 2020).
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Uniform float in [0, 1) with 24 bits of precision.
float random01(uint pixel, uint sample_index, uint dimension, uint seed) {
    uint h = pcg_hash(pixel ^ pcg_hash(sample_index ^ pcg_hash(dimension ^ pcg_hash(seed))));
    return float(h >> 8) * (1.0 / 16777216.0);
}

#endif
