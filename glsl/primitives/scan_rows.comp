#version 460
// Scan, pass 3, subgroup variant (workgroup = exactly one subgroup; ITEMS a multiple of
// 4). The tile is read and written in rows of 4 * WORKGROUP_SIZE consecutive items:
// each invocation loads one uvec4 (coalesced, a quarter of the per-lane accesses, which
// dominate on CPU implementations), the row is scanned with one subgroupInclusiveAdd of
// the lane sums and carried into the next row. No shared memory, no barriers. Partial
// rows at the end fall back to scalar accesses. Same tiles, bindings and push constants
// as scan_downsweep.comp.
#extension GL_KHR_shader_subgroup_arithmetic : require
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

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint lane = gl_LocalInvocationID.x;
    bool pred = (pc.flags & 1u) != 0u;
    bool inclusive = (pc.flags & 2u) != 0u;
    uint base = g * WORKGROUP_SIZE * ITEMS;
    uint carry = sums[g];
    uint rows = ITEMS / 4u;
    for (uint j = 0u; j < rows; ++j) {
        uint row = base + j * 4u * WORKGROUP_SIZE;
        if (row >= n) break;
        uint i = row + 4u * lane;
        uvec4 v = uvec4(0u);
        if (row + 4u * WORKGROUP_SIZE <= n) {
            v = data4[i / 4u];
        } else {
            for (uint c = 0u; c < 4u; ++c) {
                if (i + c < n) v[c] = data[i + c];
            }
        }
        if (pred) v = uvec4(notEqual(v, uvec4(0u)));
        uint s = v.x + v.y + v.z + v.w;
        uint incl = subgroupInclusiveAdd(s);
        uint run = carry + incl - s;
        uvec4 o;
        o.x = run + (inclusive ? v.x : 0u);
        run += v.x;
        o.y = run + (inclusive ? v.y : 0u);
        run += v.y;
        o.z = run + (inclusive ? v.z : 0u);
        run += v.z;
        o.w = run + (inclusive ? v.w : 0u);
        if (row + 4u * WORKGROUP_SIZE <= n) {
            outv4[i / 4u] = o;
        } else {
            for (uint c = 0u; c < 4u; ++c) {
                if (i + c < n) outv[i + c] = o[c];
            }
        }
        carry += subgroupAdd(s);
    }
}
