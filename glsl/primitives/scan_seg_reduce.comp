#version 460
// Scan, pass 1, barrier-free segment variant (CPU devices; ITEMS a multiple of 4, of 8
// for `wide64`): every invocation sums its own segment of ITEMS contiguous inputs into
// sums[segment]. No shared memory, no barrier, no subgroup operation.
//
// lavapipe (Mesa 25.0) turns a lane's buffer access into one scalar access per vector
// component, whatever the component's width, so `wide64` reads eight items per u64vec4
// (four 64-bit components) instead of four per uvec4: half the accesses (see
// Tuning::wide_accesses for the measurements). Needs shaderInt64.
//! variant wide64: WIDE64=1
#ifdef WIDE64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 4096;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer In { uint data[]; };
#ifdef WIDE64
layout(std430, set = 0, binding = 1) readonly buffer In8 { u64vec4 data8[]; };
#else
layout(std430, set = 0, binding = 1) readonly buffer In4 { uvec4 data4[]; };
#endif
layout(std430, set = 0, binding = 2) writeonly buffer Sums { uint sums[]; };
layout(push_constant) uniform Push { uint flags; } pc; // bit 0: scan (x != 0)

void main() {
    // Header kinds: 0 = segments (one per invocation), 1 = workgroups.
    if (linear_group_id() >= hdr[HDR_GROUPS + 1u]) return;
    uint seg = linear_invocation_id();
    if (seg >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint begin = seg * ITEMS;
    uint end = min(begin + ITEMS, n);
    bool pred = (pc.flags & 1u) != 0u;
    uint i = begin;
    uint s = 0u;
#ifdef WIDE64
    // Each u64vec4 holds items 2k (low half) and 2k + 1 (high half) of its eight.
    if (pred) {
        uvec4 acc = uvec4(0u);
        for (; i + 8u <= end; i += 8u) {
            u64vec4 v = data8[i / 8u];
            acc += uvec4(notEqual(uvec4(v), uvec4(0u))) + uvec4(notEqual(uvec4(v >> 32), uvec4(0u)));
        }
        s = acc.x + acc.y + acc.z + acc.w;
    } else {
        // 64-bit sums of 32-bit halves: the low 32 bits are the wrapping u32 sum.
        u64vec4 acc = u64vec4(0u);
        for (; i + 8u <= end; i += 8u) {
            u64vec4 v = data8[i / 8u];
            acc += (v & 0xFFFFFFFFul) + (v >> 32);
        }
        s = uint(acc.x + acc.y + acc.z + acc.w);
    }
#else
    uvec4 acc = uvec4(0u);
    if (pred) {
        for (; i + 4u <= end; i += 4u) acc += uvec4(notEqual(data4[i / 4u], uvec4(0u)));
    } else {
        for (; i + 4u <= end; i += 4u) acc += data4[i / 4u];
    }
    s = acc.x + acc.y + acc.z + acc.w;
#endif
    for (; i < end; ++i) {
        uint v = data[i];
        s += pred ? uint(v != 0u) : v;
    }
    sums[seg] = s;
}
