#version 460
// Reduce-by-key, barrier-free segment variant (CPU devices), pass 1: every invocation
// counts the heads of runs (i == 0 or keys[i] != keys[i - 1]) in its own segment of
// ITEMS contiguous keys and writes the count to heads[segment]; an exclusive scan of
// those gives each segment the index of its first run. No shared memory, barrier,
// atomic or subgroup operation. `wide64` (ITEMS a multiple of 8, Tuning::wide_accesses)
// reads the keys eight at a time as u64vec4s.
//! variant wide64: WIDE64=1
#ifdef WIDE64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 2048;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Heads { uint heads[]; };
#ifdef WIDE64
layout(std430, set = 0, binding = 1) readonly buffer Keys8 { u64vec4 keys8[]; };
#endif

void main() {
    // Header kinds: 0 = segments (one per invocation), 1 = workgroups.
    if (linear_group_id() >= hdr[HDR_GROUPS + 1u]) return;
    uint seg = linear_invocation_id();
    if (seg >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint begin = seg * ITEMS;
    uint end = min(begin + ITEMS, n);
    // The key before the segment; for the first segment one that differs from keys[0].
    uint prev;
    if (begin == 0u) {
        prev = ~keys[0];
    } else {
        prev = keys[begin - 1u];
    }
    uint count = 0u;
    uint i = begin;
#ifdef WIDE64
    for (; i + 8u <= end; i += 8u) {
        // Keys 2c in the low halves, 2c + 1 in the high halves; each key against the
        // one before it (the previous high half, or the last key of the previous eight).
        u64vec4 w = keys8[i / 8u];
        uvec4 lo = uvec4(w), hi = uvec4(w >> 32);
        uvec4 before_lo = uvec4(prev, hi.x, hi.y, hi.z);
        uvec4 heads4 = uvec4(notEqual(lo, before_lo)) + uvec4(notEqual(hi, lo));
        count += heads4.x + heads4.y + heads4.z + heads4.w;
        prev = hi.w;
    }
#endif
    for (; i < end; ++i) {
        uint k = keys[i];
        count += uint(k != prev);
        prev = k;
    }
    heads[seg] = count;
}
