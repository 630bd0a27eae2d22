#version 460
// Scan, pass 2 (one workgroup): exclusive scan of the tile sums in place. Each
// invocation scans a contiguous run of them sequentially: two barriers in all.
#include "grid.glsl"
#include "prim.glsl"
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) buffer Sums { uint sums[]; };

shared uint part[WORKGROUP_SIZE];

void main() {
    uint nb = hdr[HDR_GROUPS];
    uint lid = gl_LocalInvocationID.x;
    uint chunk = (nb + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    uint begin = min(lid * chunk, nb);
    uint end = min(begin + chunk, nb);
    uint s = 0u;
    for (uint i = begin; i < end; ++i) s += sums[i];
    part[lid] = s;
    barrier();
    if (lid == 0u) {
        uint run = 0u;
        for (uint w = 0u; w < WORKGROUP_SIZE; ++w) {
            uint v = part[w];
            part[w] = run;
            run += v;
        }
    }
    barrier();
    uint run = part[lid];
    for (uint i = begin; i < end; ++i) {
        uint v = sums[i];
        sums[i] = run;
        run += v;
    }
}
