#version 460
// Scan, pass 3: each invocation owns ITEMS contiguous inputs of the tile; it sums them,
// the workgroup scans the per-invocation sums (two barriers), and each invocation then
// writes its run starting from the tile's offset. In place (in == out) is allowed.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) buffer In { uint data[]; };
layout(std430, set = 0, binding = 2) readonly buffer Sums { uint sums[]; };
layout(std430, set = 0, binding = 3) buffer Out { uint outv[]; };
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
    for (uint i = begin; i < end; ++i) {
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
    for (uint i = begin; i < end; ++i) {
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
