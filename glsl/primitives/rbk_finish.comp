#version 460
// Reduce-by-key arg-min, last pass: at each head turn the run's ordered bits back into
// the f32 bits of the smallest t.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 2) readonly buffer Seg { uint seg[]; };
layout(std430, set = 0, binding = 3) buffer OutA { uint out_a[]; };

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint base = g * WORKGROUP_SIZE * ITEMS + gl_LocalInvocationID.x;
    for (uint j = 0u; j < ITEMS; ++j) {
        uint i = base + j * WORKGROUP_SIZE;
        if (i < n && (i == 0u || keys[i - 1u] != keys[i])) {
            uint s = seg[i] - 1u;
            out_a[s] = f32_unorder(out_a[s]);
        }
    }
}
