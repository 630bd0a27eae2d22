#version 460
// out[i] = the bits of random01(q.index, q.sample, q.dimension, q.seed) for query i: the
// GLSL side of the CPU twin test of src/bidir/random.rs (tests/suite/bidir_random.rs).
#include "grid.glsl"
#include "random.glsl"
struct Query {
    uint index;
    uint sample_index;
    uint dimension;
    uint seed;
};
layout(std430, set = 0, binding = 0) readonly buffer Queries { Query queries[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Out { uint bits[]; };
layout(push_constant) uniform Push { uint n; } pc;
void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    Query q = queries[i];
    bits[i] = floatBitsToUint(random01(q.index, q.sample_index, q.dimension, q.seed));
}
