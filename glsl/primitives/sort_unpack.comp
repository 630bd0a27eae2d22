#version 460
// Splits interleaved (key, value) pairs back into keys and values: the last step of a
// segment radix sort whose odd pass count left its result in the pairs scratch. Each
// invocation moves its own KEYS contiguous pairs (KEYS a multiple of 4), reading and
// writing uvec4s; tiles as in the sort.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint KEYS = 64;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Pairs { uint pairs[]; };
layout(std430, set = 0, binding = 1) readonly buffer Pairs4 { uvec4 pairs4[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Keys4 { uvec4 keys4[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Vals { uint vals[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Vals4 { uvec4 vals4[]; };

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS + 1u]) return;
    uint n = hdr[HDR_N];
    uint begin = min(linear_invocation_id() * KEYS, n);
    uint end = min(begin + KEYS, n);
    uint i = begin;
    for (; i + 4u <= end; i += 4u) {
        uvec4 p0 = pairs4[i / 2u];
        uvec4 p1 = pairs4[i / 2u + 1u];
        keys4[i / 4u] = uvec4(p0.xz, p1.xz);
        vals4[i / 4u] = uvec4(p0.yw, p1.yw);
    }
    for (; i < end; ++i) {
        keys[i] = pairs[2u * i];
        vals[i] = pairs[2u * i + 1u];
    }
}
