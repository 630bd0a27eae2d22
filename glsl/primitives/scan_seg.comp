#version 460
// Scan, pass 3, barrier-free segment variant (pairs with scan_seg_reduce.comp; ITEMS a
// multiple of 4): every invocation scans its own segment sequentially from the
// segment's scanned offset, reading and writing uvec4s. No shared memory, no barrier,
// no subgroup operation. In place (in == out) is allowed. Same bindings and push
// constants as scan_downsweep.comp.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 4096;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) buffer In { uint data[]; };
layout(std430, set = 0, binding = 1) buffer In4 { uvec4 data4[]; };
layout(std430, set = 0, binding = 2) readonly buffer Sums { uint sums[]; };
layout(std430, set = 0, binding = 3) buffer Out { uint outv[]; };
layout(std430, set = 0, binding = 3) buffer Out4 { uvec4 outv4[]; };
layout(push_constant) uniform Push { uint flags; } pc; // bit 0: scan (x != 0); bit 1: inclusive

void main() {
    // Header kinds: 0 = segments (one per invocation), 1 = workgroups.
    if (linear_group_id() >= hdr[HDR_GROUPS + 1u]) return;
    uint seg = linear_invocation_id();
    if (seg >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint begin = seg * ITEMS;
    uint end = min(begin + ITEMS, n);
    bool pred = (pc.flags & 1u) != 0u;
    bool inclusive = (pc.flags & 2u) != 0u;
    uint run = sums[seg];
    uint i = begin;
    for (; i + 4u <= end; i += 4u) {
        uvec4 v = data4[i / 4u];
        if (pred) v = uvec4(notEqual(v, uvec4(0u)));
        // Inclusive prefix within the uvec4; the exclusive one leaves each item out.
        uvec4 incl = uvec4(v.x, v.x + v.y, v.x + v.y + v.z, v.x + v.y + v.z + v.w);
        outv4[i / 4u] = uvec4(run) + (inclusive ? incl : incl - v);
        run += incl.w;
    }
    for (; i < end; ++i) {
        uint v = data[i];
        v = pred ? uint(v != 0u) : v;
        outv[i] = inclusive ? run + v : run;
        run += v;
    }
}
