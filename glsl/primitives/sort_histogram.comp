#version 460
// Radix sort pass, step 1: the digit histogram of each tile of WORKGROUP_SIZE * KEYS
// keys. Each invocation counts its own contiguous KEYS keys into its own column of
// shared counters (no atomics); two barriers per tile. The histogram is written
// digit-major (hist[digit * tiles + tile]) so one exclusive scan gives every
// (digit, tile) its global offset.
//! variant rows: ROWS=1
//! variant vec4: VEC4=1
// The `vec4` variant (KEYS a multiple of 4) reads each run as uvec4s: a quarter of the
// per-lane accesses, which dominate on CPU implementations.
// The `rows` variant assigns keys to invocations in coalesced rows instead (the
// histogram does not depend on the assignment); it pairs with sort_scatter_rows.comp.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint KEYS = 64;
layout(constant_id = 2) const uint RADIX_BITS = 8;
const uint RADIX = 1u << RADIX_BITS;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys4 { uvec4 keys4[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Hist { uint hist[]; };
// flags bit 1: also store the per-invocation counts (lane_counts[tile][digit][lane]) so
// the scatter need not count again.
layout(std430, set = 0, binding = 3) writeonly buffer LaneCounts { uint lane_counts[]; };
layout(push_constant) uniform Push { uint shift; uint bits; uint flags; } pc;

shared uint counts[RADIX * WORKGROUP_SIZE];

void main() {
    uint g = linear_group_id();
    uint tiles = hdr[HDR_GROUPS + 1u];
    if (g >= tiles) return;
    uint n = hdr[HDR_N];
    uint lid = gl_LocalInvocationID.x;
    for (uint j = lid; j < RADIX * WORKGROUP_SIZE; j += WORKGROUP_SIZE) counts[j] = 0u;
    barrier();
    uint mask = (1u << pc.bits) - 1u;
#ifdef ROWS
    uint base = g * WORKGROUP_SIZE * KEYS + lid;
    for (uint r = 0u; r < KEYS; ++r) {
        uint i = base + r * WORKGROUP_SIZE;
        if (i < n) {
            uint d = (keys[i] >> pc.shift) & mask;
            counts[d * WORKGROUP_SIZE + lid] += 1u;
        }
    }
#else
    uint begin = min(g * WORKGROUP_SIZE * KEYS + lid * KEYS, n);
    uint end = min(begin + KEYS, n);
    uint i = begin;
#ifdef VEC4
    for (; i + 4u <= end; i += 4u) {
        uvec4 k = keys4[i / 4u];
        for (uint c = 0u; c < 4u; ++c) {
            uint d = (k[c] >> pc.shift) & mask;
            counts[d * WORKGROUP_SIZE + lid] += 1u;
        }
    }
#endif
    for (; i < end; ++i) {
        uint d = (keys[i] >> pc.shift) & mask;
        counts[d * WORKGROUP_SIZE + lid] += 1u;
    }
#endif
    barrier();
    bool store = (pc.flags & 2u) != 0u;
    for (uint d = lid; d < RADIX; d += WORKGROUP_SIZE) {
        uint s = 0u;
        for (uint w = 0u; w < WORKGROUP_SIZE; ++w) {
            uint c = counts[d * WORKGROUP_SIZE + w];
            if (store) lane_counts[(g * RADIX + d) * WORKGROUP_SIZE + w] = c;
            s += c;
        }
        hist[d * tiles + g] = s;
    }
}
