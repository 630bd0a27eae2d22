#version 460
// dst_a[i] = src_a[i] (and dst_b[i] = src_b[i] if flags bit 0) for i < n: moves a sort's
// result back into the caller's buffers after an odd number of passes.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer SrcA { uint src_a[]; };
layout(std430, set = 0, binding = 2) readonly buffer SrcB { uint src_b[]; };
layout(std430, set = 0, binding = 3) writeonly buffer DstA { uint dst_a[]; };
layout(std430, set = 0, binding = 4) writeonly buffer DstB { uint dst_b[]; };
layout(push_constant) uniform Push { uint flags; } pc;

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint base = g * WORKGROUP_SIZE * ITEMS + gl_LocalInvocationID.x;
    bool both = (pc.flags & 1u) != 0u;
    for (uint j = 0u; j < ITEMS; ++j) {
        uint i = base + j * WORKGROUP_SIZE;
        if (i < n) {
            dst_a[i] = src_a[i];
            if (both) dst_b[i] = src_b[i];
        }
    }
}
