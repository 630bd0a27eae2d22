#version 460
// Reduce-by-key, pass 1: head[i] = 1 where a run of equal keys starts.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Head { uint head[]; };

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint base = g * WORKGROUP_SIZE * ITEMS + gl_LocalInvocationID.x;
    for (uint j = 0u; j < ITEMS; ++j) {
        uint i = base + j * WORKGROUP_SIZE;
        if (i < n) head[i] = (i == 0u || keys[i] != keys[i - 1u]) ? 1u : 0u;
    }
}
