#version 460
// Stream compaction, barrier-free segment variant (CPU devices; ITEMS a multiple of 4,
// the segment scan's): after the scan's first two passes over (flag != 0), sums[seg] is
// the number of kept items before this invocation's segment, so the invocation walks
// its segment and writes its kept items in order from there. No per-item position
// array is written or read back (the general path scans into one). The segment holding
// the last item writes the kept count. Same bindings as compact_scatter.comp with the
// segment sums in place of the positions. `wide64` (ITEMS a multiple of 8,
// Tuning::wide_accesses) reads flags and sources eight at a time as u64vec4s: per eight
// items one lavapipe lane access each instead of two and one per kept item.
//! variant wide64: WIDE64=1
#ifdef WIDE64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 2048;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Flags { uint flag[]; };
layout(std430, set = 0, binding = 1) readonly buffer Flags4 { uvec4 flag4[]; };
layout(std430, set = 0, binding = 2) readonly buffer Sums { uint sums[]; };
layout(std430, set = 0, binding = 3) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Out { uint outv[]; };
layout(std430, set = 0, binding = 5) writeonly buffer Count { uint count[]; };
layout(push_constant) uniform Push { uint flags; } pc; // bit 0: write indices
#ifdef WIDE64
layout(std430, set = 0, binding = 1) readonly buffer Flags8 { u64vec4 flag8[]; };
layout(std430, set = 0, binding = 3) readonly buffer Src8 { u64vec4 src8[]; };
#endif

void main() {
    // Header kinds (the scan's): 0 = segments (one per invocation), 1 = workgroups.
    if (linear_group_id() >= hdr[HDR_GROUPS + 1u]) return;
    uint seg = linear_invocation_id();
    if (seg >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint begin = seg * ITEMS;
    uint end = min(begin + ITEMS, n);
    bool indices = (pc.flags & 1u) != 0u;
    uint p = sums[seg];
    uint i = begin;
#ifdef WIDE64
    for (; i + 8u <= end; i += 8u) {
        // Items 2c in the low halves, 2c + 1 in the high halves.
        u64vec4 fw = flag8[i / 8u];
        bvec4 keep_lo = notEqual(uvec4(fw), uvec4(0u));
        bvec4 keep_hi = notEqual(uvec4(fw >> 32), uvec4(0u));
        uvec4 v_lo = uvec4(i) + uvec4(0u, 2u, 4u, 6u);
        uvec4 v_hi = v_lo + 1u;
        if (!indices) {
            u64vec4 sw = src8[i / 8u];
            v_lo = uvec4(sw);
            v_hi = uvec4(sw >> 32);
        }
        for (uint c = 0u; c < 4u; ++c) {
            if (keep_lo[c]) {
                outv[p] = v_lo[c];
                ++p;
            }
            if (keep_hi[c]) {
                outv[p] = v_hi[c];
                ++p;
            }
        }
    }
#endif
    for (; i + 4u <= end; i += 4u) {
        bvec4 keep = notEqual(flag4[i / 4u], uvec4(0u));
        for (uint c = 0u; c < 4u; ++c) {
            if (keep[c]) {
                outv[p] = indices ? i + c : src[i + c];
                ++p;
            }
        }
    }
    for (; i < end; ++i) {
        if (flag[i] != 0u) {
            outv[p] = indices ? i : src[i];
            ++p;
        }
    }
    if (end == n) count[0] = p;
}
