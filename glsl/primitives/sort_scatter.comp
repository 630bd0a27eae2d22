#version 460
// Radix sort pass, step 3: stable scatter. Each invocation recounts its own contiguous
// KEYS keys, the workgroup turns the per-invocation counts into offsets (digit by digit,
// invocations in order, starting at the tile's scanned global offset), then each
// invocation writes its keys (and values) in their original order. Stable without any
// cross-workgroup communication; three barriers per tile.
//! variant vec4: VEC4=1
// The `vec4` variant (KEYS a multiple of 4) reads keys and values as uvec4s: a quarter of
// the per-lane reads, which dominate on CPU implementations.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint KEYS = 64;
layout(constant_id = 2) const uint RADIX_BITS = 8;
const uint RADIX = 1u << RADIX_BITS;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, set = 0, binding = 2) readonly buffer ValsIn { uint vals_in[]; };
layout(std430, set = 0, binding = 1) readonly buffer KeysIn4 { uvec4 keys_in4[]; };
layout(std430, set = 0, binding = 2) readonly buffer ValsIn4 { uvec4 vals_in4[]; };
layout(std430, set = 0, binding = 3) readonly buffer Hist { uint hist[]; };
layout(std430, set = 0, binding = 4) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, set = 0, binding = 5) writeonly buffer ValsOut { uint vals_out[]; };
// Written by the histogram pass when flags bit 1 is set: then no recount here.
layout(std430, set = 0, binding = 6) readonly buffer LaneCounts { uint lane_counts[]; };
layout(push_constant) uniform Push { uint shift; uint bits; uint flags; } pc; // bit 0: values

shared uint counts[RADIX * WORKGROUP_SIZE];

void main() {
    uint g = linear_group_id();
    uint tiles = hdr[HDR_GROUPS + 1u];
    if (g >= tiles) return;
    uint n = hdr[HDR_N];
    uint lid = gl_LocalInvocationID.x;
    bool stored = (pc.flags & 2u) != 0u;
    uint mask = (1u << pc.bits) - 1u;
    uint begin = min(g * WORKGROUP_SIZE * KEYS + lid * KEYS, n);
    uint end = min(begin + KEYS, n);
    uint i = begin;
    if (stored) {
        for (uint j = lid; j < RADIX * WORKGROUP_SIZE; j += WORKGROUP_SIZE) {
            counts[j] = lane_counts[g * RADIX * WORKGROUP_SIZE + j];
        }
        i = end; // nothing to recount
    } else {
        for (uint j = lid; j < RADIX * WORKGROUP_SIZE; j += WORKGROUP_SIZE) counts[j] = 0u;
    }
    barrier();
#ifdef VEC4
    for (; i + 4u <= end; i += 4u) {
        uvec4 k = keys_in4[i / 4u];
        for (uint c = 0u; c < 4u; ++c) {
            uint d = (k[c] >> pc.shift) & mask;
            counts[d * WORKGROUP_SIZE + lid] += 1u;
        }
    }
#endif
    for (; i < end; ++i) {
        uint d = (keys_in[i] >> pc.shift) & mask;
        counts[d * WORKGROUP_SIZE + lid] += 1u;
    }
    barrier();
    for (uint d = lid; d < RADIX; d += WORKGROUP_SIZE) {
        uint run = hist[d * tiles + g];
        for (uint w = 0u; w < WORKGROUP_SIZE; ++w) {
            uint v = counts[d * WORKGROUP_SIZE + w];
            counts[d * WORKGROUP_SIZE + w] = run;
            run += v;
        }
    }
    barrier();
    bool values = (pc.flags & 1u) != 0u;
    i = begin;
#ifdef VEC4
    for (; i + 4u <= end; i += 4u) {
        uvec4 k = keys_in4[i / 4u];
        uvec4 v = values ? vals_in4[i / 4u] : uvec4(0u);
        for (uint c = 0u; c < 4u; ++c) {
            uint d = (k[c] >> pc.shift) & mask;
            uint pos = counts[d * WORKGROUP_SIZE + lid];
            counts[d * WORKGROUP_SIZE + lid] = pos + 1u;
            keys_out[pos] = k[c];
            if (values) vals_out[pos] = v[c];
        }
    }
#endif
    for (; i < end; ++i) {
        uint k = keys_in[i];
        uint d = (k >> pc.shift) & mask;
        uint pos = counts[d * WORKGROUP_SIZE + lid];
        counts[d * WORKGROUP_SIZE + lid] = pos + 1u;
        keys_out[pos] = k;
        if (values) vals_out[pos] = vals_in[i];
    }
}
