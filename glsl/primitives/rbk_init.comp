#version 460
// Reduce-by-key, pass 2 (seg = inclusive scan of the heads, so run s = seg[i] - 1):
// at each head write the unique key and the reduction's identity; the last item writes
// the number of runs. flags bit 0: arg-min (identity 0xFFFFFFFF in both outputs).
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 2) readonly buffer Seg { uint seg[]; };
layout(std430, set = 0, binding = 3) writeonly buffer OutKeys { uint out_keys[]; };
layout(std430, set = 0, binding = 4) writeonly buffer OutA { uint out_a[]; };
layout(std430, set = 0, binding = 5) writeonly buffer OutB { uint out_b[]; };
layout(std430, set = 0, binding = 6) writeonly buffer Count { uint count[]; };
layout(push_constant) uniform Push { uint flags; } pc;

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint base = g * WORKGROUP_SIZE * ITEMS + gl_LocalInvocationID.x;
    bool argmin = (pc.flags & 1u) != 0u;
    for (uint j = 0u; j < ITEMS; ++j) {
        uint i = base + j * WORKGROUP_SIZE;
        if (i < n) {
            uint k = keys[i];
            uint s = seg[i];
            if (i == 0u || keys[i - 1u] != k) {
                out_keys[s - 1u] = k;
                if (argmin) {
                    out_a[s - 1u] = 0xFFFFFFFFu;
                    out_b[s - 1u] = 0xFFFFFFFFu;
                } else {
                    out_a[s - 1u] = 0u;
                }
            }
            if (i == n - 1u) count[0] = s;
        }
    }
}
