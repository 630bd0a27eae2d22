#version 460
// Scan, pass 2 (one workgroup): exclusive scan of the tile sums in place
// (workgroup_scan.glsl: each invocation scans a contiguous run; two barriers in all).
#include "grid.glsl"
#include "prim.glsl"
#include "workgroup_scan.glsl"
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) buffer Sums { uint sums[]; };

void main() {
    WORKGROUP_SCAN(sums, sums, hdr[HDR_GROUPS], false, false)
}
