#version 460
// Scan of a short array in one dispatch of one workgroup (Scan::record with a host count
// of at most SMALL_SCAN_MAX items; workgroup_scan.glsl). The three-pass scan spends
// most of its time on a short array in dispatch overhead and the barriers between its
// passes (PDACRT scans arrays of a few thousand words per level); this is one dispatch.
// In place (in == out) is allowed.
#include "grid.glsl"
#include "workgroup_scan.glsl"
layout(std430, set = 0, binding = 0) readonly buffer In { uint data[]; } src;
layout(std430, set = 0, binding = 1) writeonly buffer Out { uint data[]; } dst;
layout(push_constant) uniform Push {
    uint n;
    uint flags;  // bit 0: scan (x != 0); bit 1: inclusive
} pc;

void main() {
    WORKGROUP_SCAN(src.data, dst.data, pc.n, (pc.flags & 1u) != 0u, (pc.flags & 2u) != 0u)
}
