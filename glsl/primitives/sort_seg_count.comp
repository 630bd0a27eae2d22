#version 460
// Radix sort pass, step 1, barrier-free segment variant (CPU devices). Each invocation
// owns KEYS contiguous keys (its segment: KEYS a multiple of 4, read as uvec4s, or of 8,
// read as u64vec4s with `wide64`) and counts their digits into its own column of shared
// counters, then writes the counts digit-major across all segments
// (hist[digit * segments + segment]), so one exclusive
// scan gives every (digit, segment) its global offset in stable order. No invocation
// touches another's counters: no barrier anywhere (barriers are slow on lavapipe).
//! variant wide64: WIDE64=1
#ifdef WIDE64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint KEYS = 64;
layout(constant_id = 2) const uint RADIX_BITS = 8;
const uint RADIX = 1u << RADIX_BITS;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys4 { uvec4 keys4[]; };
#ifdef WIDE64
// `wide64`: 64-bit components, half the per-lane accesses on lavapipe (Tuning::wide_accesses).
layout(std430, set = 0, binding = 1) readonly buffer Keys8 { u64vec4 keys8[]; };
#endif
layout(std430, set = 0, binding = 2) writeonly buffer Hist { uint hist[]; };
// flags bit 2: the keys are the even words of interleaved (key, value) pairs.
layout(push_constant) uniform Push { uint shift; uint bits; uint flags; } pc;

shared uint counts[RADIX * WORKGROUP_SIZE];

// Counts four digits (counter indices `d`): the loads together, then the stores in
// order (earlier_equal in prim.glsl).
void count4(uvec4 d) {
    uvec4 c = uvec4(counts[d.x], counts[d.y], counts[d.z], counts[d.w]) + earlier_equal(d);
    counts[d.x] = c.x + 1u;
    counts[d.y] = c.y + 1u;
    counts[d.z] = c.z + 1u;
    counts[d.w] = c.w + 1u;
}

void main() {
    uint g = linear_group_id();
    uint tiles = hdr[HDR_GROUPS + 1u];
    if (g >= tiles) return;
    uint n = hdr[HDR_N];
    // A one-invocation workgroup never names its invocation, so that the whole kernel
    // stays uniform: lavapipe then runs it as scalar code with scalar memory accesses.
    uint lid = WORKGROUP_SIZE == 1u ? 0u : gl_LocalInvocationID.x;
    uint segments = tiles * WORKGROUP_SIZE;
    uint seg = g * WORKGROUP_SIZE + lid;
    for (uint d = 0u; d < RADIX; ++d) counts[d * WORKGROUP_SIZE + lid] = 0u;
    uint mask = (1u << pc.bits) - 1u;
    uint begin = min(seg * KEYS, n);
    uint end = min(begin + KEYS, n);
    uint i = begin;
    if ((pc.flags & 4u) != 0u) {
        // Two pairs per uvec4; begin is a multiple of 4, so each read is aligned.
        for (; i + 4u <= end; i += 4u) {
#ifdef WIDE64
            // Four pairs per u64vec4, keys in the low halves.
            uvec4 k = uvec4(keys8[i / 4u]);
#else
            uvec4 k = uvec4(keys4[i / 2u].xz, keys4[i / 2u + 1u].xz);
#endif
            count4(((k >> pc.shift) & mask) * WORKGROUP_SIZE + lid);
        }
        for (; i < end; ++i) {
            uint d = (keys[2u * i] >> pc.shift) & mask;
            counts[d * WORKGROUP_SIZE + lid] += 1u;
        }
    }
#ifdef WIDE64
    // Eight keys per u64vec4 (begin is a multiple of 8 for KEYS a multiple of 8, and
    // counting needs no order).
    for (; i + 8u <= end; i += 8u) {
        u64vec4 w = keys8[i / 8u];
        count4(((uvec4(w) >> pc.shift) & mask) * WORKGROUP_SIZE + lid);
        count4(((uvec4(w >> 32) >> pc.shift) & mask) * WORKGROUP_SIZE + lid);
    }
#endif
    for (; i + 4u <= end; i += 4u) {
        count4(((keys4[i / 4u] >> pc.shift) & mask) * WORKGROUP_SIZE + lid);
    }
    for (; i < end; ++i) {
        uint d = (keys[i] >> pc.shift) & mask;
        counts[d * WORKGROUP_SIZE + lid] += 1u;
    }
    for (uint d = 0u; d < RADIX; ++d) hist[d * segments + seg] = counts[d * WORKGROUP_SIZE + lid];
}
