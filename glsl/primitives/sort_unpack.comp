#version 460
// Splits interleaved (key, value) pairs back into keys and values: the last step of a
// key-value segment radix sort that left its result in the pairs scratch (after a
// single pass; with `wide64`, after any number, RadixSort::splits_last). Each invocation
// moves its own KEYS contiguous pairs (KEYS a multiple of 4, of 8 for `wide64`),
// reading and writing uvec4s, or u64vec4s with `wide64`; tiles as in the sort.
//! variant wide64: WIDE64=1
#ifdef WIDE64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif
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
#ifdef WIDE64
layout(std430, set = 0, binding = 1) readonly buffer Pairs8 { u64vec4 pairs8[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Keys8 { u64vec4 keys8[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Vals8 { u64vec4 vals8[]; };
#endif

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS + 1u]) return;
    uint n = hdr[HDR_N];
    uint begin = min(linear_invocation_id() * KEYS, n);
    uint end = min(begin + KEYS, n);
    uint i = begin;
#ifdef WIDE64
    for (; i + 8u <= end; i += 8u) {
        // Pairs i..i+7; keys in the low halves. Pack two per 64-bit word (item 2c low).
        u64vec4 a = pairs8[i / 4u];
        u64vec4 b = pairs8[i / 4u + 1u];
        uvec4 ka = uvec4(a), kb = uvec4(b), va = uvec4(a >> 32), vb = uvec4(b >> 32);
        keys8[i / 8u] = u64vec4(uvec4(ka.x, ka.z, kb.x, kb.z))
            | (u64vec4(uvec4(ka.y, ka.w, kb.y, kb.w)) << 32);
        vals8[i / 8u] = u64vec4(uvec4(va.x, va.z, vb.x, vb.z))
            | (u64vec4(uvec4(va.y, va.w, vb.y, vb.w)) << 32);
    }
#endif
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
