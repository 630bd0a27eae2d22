#version 460
// Stream compaction, last pass: pos = exclusive scan of (flag != 0). Kept items go to
// out[pos[i]] (the item, or its index i with flags bit 0); the last invocation writes
// the kept count.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Flags { uint flag[]; };
layout(std430, set = 0, binding = 2) readonly buffer Pos { uint pos[]; };
layout(std430, set = 0, binding = 3) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Out { uint outv[]; };
layout(std430, set = 0, binding = 5) writeonly buffer Count { uint count[]; };
layout(push_constant) uniform Push { uint flags; } pc;

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint base = g * WORKGROUP_SIZE * ITEMS + gl_LocalInvocationID.x;
    bool indices = (pc.flags & 1u) != 0u;
    for (uint j = 0u; j < ITEMS; ++j) {
        uint i = base + j * WORKGROUP_SIZE;
        if (i < n) {
            bool keep = flag[i] != 0u;
            uint p = pos[i];
            if (keep) outv[p] = indices ? i : src[i];
            if (i == n - 1u) count[0] = p + uint(keep);
        }
    }
}
