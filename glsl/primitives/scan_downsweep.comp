#version 460
// Scan, pass 3: each invocation owns ITEMS contiguous inputs of the tile; it sums them,
// the workgroup scans the per-invocation sums (two barriers), and each invocation then
// writes its run starting from the tile's offset. In place (in == out) is allowed.
//! variant vec4: VEC4=1
// The vec4 variant (ITEMS a multiple of 4) reads and writes each run as uvec4s.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) buffer In { uint data[]; };
layout(std430, set = 0, binding = 1) buffer In4 { uvec4 data4[]; };
layout(std430, set = 0, binding = 2) readonly buffer Sums { uint sums[]; };
layout(std430, set = 0, binding = 3) buffer Out { uint outv[]; };
layout(std430, set = 0, binding = 3) buffer Out4 { uvec4 outv4[]; };
layout(push_constant) uniform Push { uint flags; } pc; // bit 0: scan (x != 0); bit 1: inclusive

shared uint part[WORKGROUP_SIZE];

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint lid = gl_LocalInvocationID.x;
    uint begin = min(g * WORKGROUP_SIZE * ITEMS + lid * ITEMS, n);
    uint end = min(begin + ITEMS, n);
    bool pred = (pc.flags & 1u) != 0u;
    bool inclusive = (pc.flags & 2u) != 0u;
    uint s = 0u;
    uint i = begin;
#ifdef VEC4
    for (; i + 4u <= end; i += 4u) {
        uvec4 v = data4[i / 4u];
        if (pred) v = uvec4(notEqual(v, uvec4(0u)));
        s += v.x + v.y + v.z + v.w;
    }
#endif
    for (; i < end; ++i) {
        uint v = data[i];
        s += pred ? uint(v != 0u) : v;
    }
    part[lid] = s;
    barrier();
    if (lid == 0u) {
        uint run = sums[g];
        for (uint w = 0u; w < WORKGROUP_SIZE; ++w) {
            uint v = part[w];
            part[w] = run;
            run += v;
        }
    }
    barrier();
    uint run = part[lid];
    i = begin;
#ifdef VEC4
    for (; i + 4u <= end; i += 4u) {
        uvec4 v = data4[i / 4u];
        if (pred) v = uvec4(notEqual(v, uvec4(0u)));
        uvec4 o;
        o.x = run + (inclusive ? v.x : 0u);
        run += v.x;
        o.y = run + (inclusive ? v.y : 0u);
        run += v.y;
        o.z = run + (inclusive ? v.z : 0u);
        run += v.z;
        o.w = run + (inclusive ? v.w : 0u);
        run += v.w;
        outv4[i / 4u] = o;
    }
#endif
    for (; i < end; ++i) {
        uint v = data[i];
        v = pred ? uint(v != 0u) : v;
        if (inclusive) {
            run += v;
            outv[i] = run;
        } else {
            outv[i] = run;
            run += v;
        }
    }
}
