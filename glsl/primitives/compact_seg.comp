#version 460
// Stream compaction, barrier-free segment variant (CPU devices; ITEMS a multiple of 4,
// the segment scan's): after the scan's first two passes over (flag != 0), sums[seg] is
// the number of kept items before this invocation's segment, so the invocation walks
// its segment and writes its kept items in order from there. No per-item position
// array is written or read back (the general path scans into one). The segment holding
// the last item writes the kept count. Same bindings as compact_scatter.comp with the
// segment sums in place of the positions.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 2048;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Flags { uint flag[]; };
layout(std430, set = 0, binding = 1) readonly buffer Flags4 { uvec4 flag4[]; };
layout(std430, set = 0, binding = 2) readonly buffer Sums { uint sums[]; };
layout(std430, set = 0, binding = 3) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Out { uint outv[]; };
layout(std430, set = 0, binding = 5) writeonly buffer Count { uint count[]; };
layout(push_constant) uniform Push { uint flags; } pc; // bit 0: write indices

void main() {
    // Header kinds (the scan's): 0 = segments (one per invocation), 1 = workgroups.
    if (linear_group_id() >= hdr[HDR_GROUPS + 1u]) return;
    uint seg = linear_invocation_id();
    if (seg >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint begin = seg * ITEMS;
    uint end = min(begin + ITEMS, n);
    bool indices = (pc.flags & 1u) != 0u;
    uint p = sums[seg];
    uint i = begin;
    for (; i + 4u <= end; i += 4u) {
        bvec4 keep = notEqual(flag4[i / 4u], uvec4(0u));
        for (uint c = 0u; c < 4u; ++c) {
            if (keep[c]) {
                outv[p] = indices ? i + c : src[i + c];
                ++p;
            }
        }
    }
    for (; i < end; ++i) {
        if (flag[i] != 0u) {
            outv[p] = indices ? i : src[i];
            ++p;
        }
    }
    if (end == n) count[0] = p;
}
