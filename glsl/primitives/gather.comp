#version 460
// flags bit 0 clear (gather): out[i] = src[idx[i]] (0 where idx[i] >= len).
// flags bit 0 set (scatter):  out[idx[i]] = src[i] (skipped where idx[i] >= len).
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 2) readonly buffer Idx { uint idx[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Out { uint outv[]; };
layout(push_constant) uniform Push { uint len; uint flags; } pc;

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint base = g * WORKGROUP_SIZE * ITEMS + gl_LocalInvocationID.x;
    bool scatter = (pc.flags & 1u) != 0u;
    for (uint j = 0u; j < ITEMS; ++j) {
        uint i = base + j * WORKGROUP_SIZE;
        if (i < n) {
            uint k = idx[i];
            if (scatter) {
                if (k < pc.len) outv[k] = src[i];
            } else {
                outv[i] = k < pc.len ? src[k] : 0u;
            }
        }
    }
}
