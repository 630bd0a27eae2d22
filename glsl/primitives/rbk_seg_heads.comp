#version 460
// Reduce-by-key, barrier-free segment variant (CPU devices), pass 1: every invocation
// counts the heads of runs (i == 0 or keys[i] != keys[i - 1]) in its own segment of
// ITEMS contiguous keys and writes the count to heads[segment]; an exclusive scan of
// those gives each segment the index of its first run. No shared memory, barrier,
// atomic or subgroup operation.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 2048;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Heads { uint heads[]; };

void main() {
    // Header kinds: 0 = segments (one per invocation), 1 = workgroups.
    if (linear_group_id() >= hdr[HDR_GROUPS + 1u]) return;
    uint seg = linear_invocation_id();
    if (seg >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint begin = seg * ITEMS;
    uint end = min(begin + ITEMS, n);
    // The key before the segment; for the first segment one that differs from keys[0].
    uint prev;
    if (begin == 0u) {
        prev = ~keys[0];
    } else {
        prev = keys[begin - 1u];
    }
    uint count = 0u;
    for (uint i = begin; i < end; ++i) {
        uint k = keys[i];
        count += uint(k != prev);
        prev = k;
    }
    heads[seg] = count;
}
