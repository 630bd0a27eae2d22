#version 460
// Scan, pass 1: the sum of each tile of WORKGROUP_SIZE * ITEMS inputs (coalesced reads;
// the order does not matter for a sum).
//! variant vec4: VEC4=1
// The vec4 variant (ITEMS a multiple of 4) loads uvec4s: a quarter of the per-lane
// accesses, which dominate on CPU implementations.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer In { uint data[]; };
layout(std430, set = 0, binding = 1) readonly buffer In4 { uvec4 data4[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Sums { uint sums[]; };
layout(push_constant) uniform Push { uint flags; } pc; // bit 0: scan (x != 0)

shared uint part[WORKGROUP_SIZE];

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint lid = gl_LocalInvocationID.x;
    uint base = g * WORKGROUP_SIZE * ITEMS + lid;
    bool pred = (pc.flags & 1u) != 0u;
    uint s = 0u;
#ifdef VEC4
    uint base4 = g * WORKGROUP_SIZE * (ITEMS / 4u) + lid;
    for (uint j = 0u; j < ITEMS / 4u; ++j) {
        uint q = base4 + j * WORKGROUP_SIZE;
        uvec4 v = uvec4(0u);
        if (4u * q + 4u <= n) {
            v = data4[q];
        } else {
            for (uint c = 0u; c < 4u; ++c) {
                if (4u * q + c < n) v[c] = data[4u * q + c];
            }
        }
        if (pred) v = uvec4(notEqual(v, uvec4(0u)));
        s += v.x + v.y + v.z + v.w;
    }
#else
    for (uint j = 0u; j < ITEMS; ++j) {
        uint i = base + j * WORKGROUP_SIZE;
        if (i < n) {
            uint v = data[i];
            s += pred ? uint(v != 0u) : v;
        }
    }
#endif
    part[lid] = s;
    barrier();
    if (lid == 0u) {
        uint t = 0u;
        for (uint w = 0u; w < WORKGROUP_SIZE; ++w) t += part[w];
        sums[g] = t;
    }
}
