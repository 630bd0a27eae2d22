#version 460
// flags bit 0 clear (gather): out[i] = src[idx[i]] (0 where idx[i] >= len).
// flags bit 0 set (scatter):  out[idx[i]] = src[i] (skipped where idx[i] >= len).
//
// Default: subgroup rows (item i of a workgroup's tile at invocation i % size).
// `seg64` (CPU devices, Tuning::wide_accesses; Gather uses it for gathers): each
// invocation moves its own segment of ITEMS contiguous items (a multiple of 8), reading
// the indices and writing the outputs eight at a time as u64vec4s, so only the indexed
// loads cost a lavapipe lane access per item; it clamps each index before the load and
// selects 0 after, so the load needs no branch. Needs shaderInt64.
//! variant seg64: SEG64=1
#ifdef SEG64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 2) readonly buffer Idx { uint idx[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Out { uint outv[]; };
layout(push_constant) uniform Push { uint len; uint flags; } pc;
#ifdef SEG64
layout(std430, set = 0, binding = 2) readonly buffer Idx8 { u64vec4 idx8[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Out8 { u64vec4 outv8[]; };

// Four gathered values, 0 for indices past the end (len > 0).
uvec4 gather4(uvec4 k) {
    uint last = pc.len - 1u;
    uvec4 v = uvec4(src[min(k.x, last)], src[min(k.y, last)], src[min(k.z, last)],
                    src[min(k.w, last)]);
    return mix(uvec4(0u), v, lessThan(k, uvec4(pc.len)));
}
#endif

// One item the general way (any len, any position).
void move1(uint i, bool scatter) {
    uint k = idx[i];
    if (scatter) {
        if (k < pc.len) outv[k] = src[i];
    } else {
        outv[i] = k < pc.len ? src[k] : 0u;
    }
}

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    bool scatter = (pc.flags & 1u) != 0u;
#ifdef SEG64
    uint seg = linear_invocation_id();
    uint begin = min(seg * ITEMS, n);
    uint end = min(begin + ITEMS, n);
    uint i = begin;
    // Each u64vec4 holds items 2c (low halves) and 2c + 1 (high halves) of its eight.
    // (Scatters, which Gather runs with the rows kernel, take the general path.)
    if (!scatter && pc.len > 0u) {
        for (; i + 8u <= end; i += 8u) {
            u64vec4 kw = idx8[i / 8u];
            uvec4 lo = gather4(uvec4(kw));
            uvec4 hi = gather4(uvec4(kw >> 32));
            outv8[i / 8u] = u64vec4(lo) | (u64vec4(hi) << 32);
        }
    }
    for (; i < end; ++i) move1(i, scatter);
#else
    uint base = g * WORKGROUP_SIZE * ITEMS + gl_LocalInvocationID.x;
    for (uint j = 0u; j < ITEMS; ++j) {
        uint i = base + j * WORKGROUP_SIZE;
        if (i < n) move1(i, scatter);
    }
#endif
}
