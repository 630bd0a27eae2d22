#version 460
// Scan, pass 3, barrier-free segment variant (pairs with scan_seg_reduce.comp; ITEMS a
// multiple of 4, of 8 for `wide64`): every invocation scans its own segment
// sequentially from the segment's scanned offset. No shared memory, no barrier, no
// subgroup operation. In place (in == out) is allowed. Same bindings and push constants
// as scan_downsweep.comp. `wide64` reads and writes eight items per u64vec4 instead of
// four per uvec4 (half the per-lane accesses on lavapipe; scan_seg_reduce.comp).
//! variant wide64: WIDE64=1
#ifdef WIDE64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 4096;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) buffer In { uint data[]; };
layout(std430, set = 0, binding = 2) readonly buffer Sums { uint sums[]; };
layout(std430, set = 0, binding = 3) buffer Out { uint outv[]; };
#ifdef WIDE64
layout(std430, set = 0, binding = 1) buffer In8 { u64vec4 data8[]; };
layout(std430, set = 0, binding = 3) buffer Out8 { u64vec4 outv8[]; };
#else
layout(std430, set = 0, binding = 1) buffer In4 { uvec4 data4[]; };
layout(std430, set = 0, binding = 3) buffer Out4 { uvec4 outv4[]; };
#endif
layout(push_constant) uniform Push { uint flags; } pc; // bit 0: scan (x != 0); bit 1: inclusive

// Inclusive prefix sums within a uvec4.
uvec4 inclusive4(uvec4 v) {
    return uvec4(v.x, v.x + v.y, v.x + v.y + v.z, v.x + v.y + v.z + v.w);
}

void main() {
    // Header kinds: 0 = segments (one per invocation), 1 = workgroups.
    if (linear_group_id() >= hdr[HDR_GROUPS + 1u]) return;
    uint seg = linear_invocation_id();
    if (seg >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint begin = seg * ITEMS;
    uint end = min(begin + ITEMS, n);
    bool pred = (pc.flags & 1u) != 0u;
    bool inclusive = (pc.flags & 2u) != 0u;
    uint run = sums[seg];
    uint i = begin;
#ifdef WIDE64
    for (; i + 8u <= end; i += 8u) {
        // Items 2k in the low halves (lo[k]), 2k + 1 in the high halves (hi[k]).
        u64vec4 v = data8[i / 8u];
        uvec4 lo = uvec4(v);
        uvec4 hi = uvec4(v >> 32);
        if (pred) {
            lo = uvec4(notEqual(lo, uvec4(0u)));
            hi = uvec4(notEqual(hi, uvec4(0u)));
        }
        uvec4 pairs = lo + hi;
        uvec4 upto = inclusive4(pairs);         // inclusive sum through item 2k + 1
        uvec4 before = uvec4(run) + upto - pairs; // exclusive sum before item 2k
        uvec4 out_lo = inclusive ? before + lo : before;
        uvec4 out_hi = inclusive ? uvec4(run) + upto : before + lo;
        outv8[i / 8u] = u64vec4(out_lo) | (u64vec4(out_hi) << 32);
        run += upto.w;
    }
#else
    for (; i + 4u <= end; i += 4u) {
        uvec4 v = data4[i / 4u];
        if (pred) v = uvec4(notEqual(v, uvec4(0u)));
        // Inclusive prefix within the uvec4; the exclusive one leaves each item out.
        uvec4 incl = inclusive4(v);
        outv4[i / 4u] = uvec4(run) + (inclusive ? incl : incl - v);
        run += incl.w;
    }
#endif
    for (; i < end; ++i) {
        uint v = data[i];
        v = pred ? uint(v != 0u) : v;
        outv[i] = inclusive ? run + v : run;
        run += v;
    }
}
