#version 460
// Scan, pass 3, subgroup variant (workgroup = exactly one subgroup): the tile is read
// and written in rows of WORKGROUP_SIZE consecutive items (coalesced), each row scanned
// with one subgroupInclusiveAdd and carried into the next. No shared memory, no
// barriers: on CPU devices every row is a few SIMD instructions. Same tiles, bindings
// and push constants as scan_downsweep.comp.
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) buffer In { uint data[]; };
layout(std430, set = 0, binding = 2) readonly buffer Sums { uint sums[]; };
layout(std430, set = 0, binding = 3) buffer Out { uint outv[]; };
layout(push_constant) uniform Push { uint flags; } pc; // bit 0: scan (x != 0); bit 1: inclusive

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint lane = gl_LocalInvocationID.x;
    bool pred = (pc.flags & 1u) != 0u;
    bool inclusive = (pc.flags & 2u) != 0u;
    uint base = g * WORKGROUP_SIZE * ITEMS;
    uint carry = sums[g];
    for (uint j = 0u; j < ITEMS; ++j) {
        uint row = base + j * WORKGROUP_SIZE;
        if (row >= n) break;
        uint i = row + lane;
        uint v = 0u;
        if (i < n) {
            v = data[i];
            v = pred ? uint(v != 0u) : v;
        }
        uint incl = subgroupInclusiveAdd(v);
        if (i < n) outv[i] = carry + (inclusive ? incl : incl - v);
        carry += subgroupAdd(v);
    }
}
