#version 460
// Radix sort pass, step 1, multisplit variant (GPUs): the digit histogram of each tile
// of WORKGROUP_SIZE * KEYS keys, counted with shared-memory atomics (fast on GPUs, and
// the order of counting does not matter). Keys are read in coalesced rows
// (key = tile + row * WORKGROUP_SIZE + invocation), as whole uvec4s where the tile
// allows. The histogram is written digit-major (hist[digit * tiles + tile]), so one
// exclusive scan gives every (digit, tile) its global offset; sort_ms_scatter.comp
// partitions the keys into the same tiles.
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint KEYS = 16;
layout(constant_id = 2) const uint RADIX_BITS = 8;
const uint RADIX = 1u << RADIX_BITS;
const uint TILE = WORKGROUP_SIZE * KEYS;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys4 { uvec4 keys4[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Hist { uint hist[]; };
layout(push_constant) uniform Push { uint shift; uint bits; uint flags; } pc;

shared uint counts[RADIX];

void count(uint key, uint mask) {
    atomicAdd(counts[(key >> pc.shift) & mask], 1u);
}

void main() {
    uint g = linear_group_id();
    uint tiles = hdr[HDR_GROUPS + 1u];
    if (g >= tiles) return;
    uint n = hdr[HDR_N];
    uint lid = gl_LocalInvocationID.x;
    for (uint d = lid; d < RADIX; d += WORKGROUP_SIZE) counts[d] = 0u;
    barrier();
    uint mask = (1u << pc.bits) - 1u;
    uint base = g * TILE;
    if (TILE % 4u == 0u && base + TILE <= n) {
        // A whole tile: uvec4 rows (the tile starts on a 16-byte boundary).
        for (uint r = 0u; r < KEYS / 4u; ++r) {
            uvec4 k = keys4[base / 4u + r * WORKGROUP_SIZE + lid];
            count(k.x, mask);
            count(k.y, mask);
            count(k.z, mask);
            count(k.w, mask);
        }
        // KEYS % 4 trailing rows of single keys.
        for (uint r = (KEYS / 4u) * 4u; r < KEYS; ++r) {
            count(keys[base + r * WORKGROUP_SIZE + lid], mask);
        }
    } else {
        for (uint r = 0u; r < KEYS; ++r) {
            uint i = base + r * WORKGROUP_SIZE + lid;
            if (i < n) count(keys[i], mask);
        }
    }
    barrier();
    for (uint d = lid; d < RADIX; d += WORKGROUP_SIZE) hist[d * tiles + g] = counts[d];
}
