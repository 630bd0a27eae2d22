#version 460
// Scan of a short array in one dispatch of one workgroup (Scan::record with a host count
// of at most SMALL_SCAN_MAX items): each invocation sums a contiguous run, one
// invocation scans the WORKGROUP_SIZE run sums in shared memory, and each invocation
// then scans its run from its offset. The three-dispatch scan spends most of its time on
// a short array in dispatch overhead and the barriers between its passes (PDACRT scans
// two arrays of a few thousand words per level); this is one dispatch. In place
// (in == out) is allowed: each item is read before it is written, by the same invocation.
#include "grid.glsl"
layout(std430, set = 0, binding = 0) readonly buffer In { uint data[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Out { uint outv[]; };
layout(push_constant) uniform Push {
    uint n;
    uint flags;  // bit 0: scan (x != 0); bit 1: inclusive
} pc;

shared uint run_start[WORKGROUP_SIZE];

uint item(uint i, bool pred) {
    uint v = data[i];
    return pred ? uint(v != 0u) : v;
}

void main() {
    uint lid = gl_LocalInvocationID.x;
    bool pred = (pc.flags & 1u) != 0u;
    bool inclusive = (pc.flags & 2u) != 0u;
    uint per = (pc.n + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    uint begin = min(lid * per, pc.n);
    uint end = min(begin + per, pc.n);
    uint sum = 0u;
    for (uint i = begin; i < end; ++i) sum += item(i, pred);
    run_start[lid] = sum;
    barrier();
    if (lid == 0u) {
        uint total = 0u;
        for (uint w = 0u; w < WORKGROUP_SIZE; ++w) {
            uint v = run_start[w];
            run_start[w] = total;
            total += v;
        }
    }
    barrier();
    uint run = run_start[lid];
    for (uint i = begin; i < end; ++i) {
        uint v = item(i, pred);
        outv[i] = inclusive ? run + v : run;
        run += v;
    }
}
