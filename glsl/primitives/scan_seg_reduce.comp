#version 460
// Scan, pass 1, barrier-free segment variant (CPU devices; ITEMS a multiple of 4):
// every invocation sums its own segment of ITEMS contiguous inputs, read as uvec4s,
// into sums[segment]. No shared memory, no barrier, no subgroup operation.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 4096;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer In { uint data[]; };
layout(std430, set = 0, binding = 1) readonly buffer In4 { uvec4 data4[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Sums { uint sums[]; };
layout(push_constant) uniform Push { uint flags; } pc; // bit 0: scan (x != 0)

void main() {
    // Header kinds: 0 = segments (one per invocation), 1 = workgroups.
    if (linear_group_id() >= hdr[HDR_GROUPS + 1u]) return;
    uint seg = linear_invocation_id();
    if (seg >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint begin = seg * ITEMS;
    uint end = min(begin + ITEMS, n);
    bool pred = (pc.flags & 1u) != 0u;
    uvec4 acc = uvec4(0u);
    uint i = begin;
    if (pred) {
        for (; i + 4u <= end; i += 4u) acc += uvec4(notEqual(data4[i / 4u], uvec4(0u)));
    } else {
        for (; i + 4u <= end; i += 4u) acc += data4[i / 4u];
    }
    uint s = acc.x + acc.y + acc.z + acc.w;
    for (; i < end; ++i) {
        uint v = data[i];
        s += pred ? uint(v != 0u) : v;
    }
    sums[seg] = s;
}
