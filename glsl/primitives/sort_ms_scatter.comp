#version 460
// Radix sort pass, step 3, multisplit variant (GPUs): a stable scatter of one tile of
// WORKGROUP_SIZE * KEYS keys (the tiles of sort_ms_count.comp), in four steps:
//
// 1. Rank. Subgroup s owns the s-th contiguous run of SUB = KEYS * gl_SubgroupSize keys
//    of the tile and reads it in coalesced rows (key = run + row * gl_SubgroupSize +
//    lane). Row by row, the lanes holding the same digit find each other with one ballot
//    per digit bit (warp-level multisplit, as in Onesweep: Adinets & Merrill 2022), the
//    lowest of them adds the group's size to the subgroup's own counter of that digit,
//    and each lane's rank is the counter's old value plus the number of lower lanes with
//    its digit. Rows in order and lanes in order: ranks follow the input order.
// 2. Offsets. Per digit: the tile-local start (an exclusive scan over digits of the
//    tile's digit counts) plus the counts of earlier subgroups. Subgroups partition the
//    tile in gl_SubgroupID order, so this too follows the input order: stable.
// 3. Local sort. Every key (and value) is stored in shared memory at its position
//    within the tile, so the tile is now ordered by digit.
// 4. Write. Invocation i writes the tile's elements i, i + WORKGROUP_SIZE, ... to their
//    digit's global offset (the scanned histogram) plus their place in the digit's run:
//    neighbouring invocations write neighbouring addresses, coalesced.
//
// Four barriers per tile and no cross-workgroup communication (no forward-progress
// assumption). Needs subgroup ballot and shuffle, and full subgroups (the pipeline asks
// for them): the runs of the subgroups must cover the tile exactly. MAX_SUBGROUPS is the
// workgroup size over the device's smallest subgroup size.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint KEYS = 16;
layout(constant_id = 2) const uint RADIX_BITS = 8;
layout(constant_id = 3) const uint MAX_SUBGROUPS = 8;
const uint RADIX = 1u << RADIX_BITS;
const uint TILE = WORKGROUP_SIZE * KEYS;
// Digits handled by each invocation in step 2.
const uint DIGITS_PER_INVOCATION = (RADIX + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, set = 0, binding = 2) readonly buffer ValsIn { uint vals_in[]; };
layout(std430, set = 0, binding = 3) readonly buffer Hist { uint hist[]; };
layout(std430, set = 0, binding = 4) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, set = 0, binding = 5) writeonly buffer ValsOut { uint vals_out[]; };
layout(push_constant) uniform Push { uint shift; uint bits; uint flags; } pc; // bit 0: values

// Per subgroup and digit: the subgroup's count (step 1), then the digit's tile-local
// start plus the counts of the earlier subgroups (step 2).
shared uint sub_counts[MAX_SUBGROUPS * RADIX];
// Per digit: global offset of the digit's run minus its tile-local start.
shared uint digit_out[RADIX];
// Per subgroup: the sum of its invocations' digit counts (step 2's scan).
shared uint sub_sums[MAX_SUBGROUPS];
shared uint tile_keys[TILE];
shared uint tile_vals[TILE];

void main() {
    uint g = linear_group_id();
    uint tiles = hdr[HDR_GROUPS + 1u];
    if (g >= tiles) return;
    uint n = hdr[HDR_N];
    uint lid = gl_LocalInvocationID.x;
    uint sub = gl_SubgroupID;
    uint lane = gl_SubgroupInvocationID;
    uint width = gl_SubgroupSize;
    bool values = (pc.flags & 1u) != 0u;
    uint mask = (1u << pc.bits) - 1u;
    for (uint j = lid; j < MAX_SUBGROUPS * RADIX; j += WORKGROUP_SIZE) sub_counts[j] = 0u;

    // Step 1: load the subgroup's run (all loads first, so they are in flight together).
    uint tile_base = g * TILE;
    uint run = tile_base + sub * KEYS * width + lane;
    uint key[KEYS];
    uint val[KEYS];
    for (uint r = 0u; r < KEYS; ++r) {
        uint i = run + r * width;
        key[r] = i < n ? keys_in[i] : 0u;
        val[r] = (values && i < n) ? vals_in[i] : 0u;
    }
    barrier(); // sub_counts zeroed
    uint rank[KEYS];
    for (uint r = 0u; r < KEYS; ++r) {
        bool valid = run + r * width < n;
        uint digit = (key[r] >> pc.shift) & mask;
        uvec4 peers = subgroupBallot(valid);
        for (uint b = 0u; b < pc.bits; ++b) {
            bool bit = ((digit >> b) & 1u) != 0u;
            uvec4 same = subgroupBallot(bit);
            peers &= bit ? same : ~same;
        }
        uint lower = subgroupBallotExclusiveBitCount(peers);
        uint leader = valid ? subgroupBallotFindLSB(peers) : lane;
        uint before = 0u;
        if (valid && lower == 0u) {
            before = atomicAdd(sub_counts[sub * RADIX + digit], subgroupBallotBitCount(peers));
        }
        rank[r] = subgroupShuffle(before, leader) + lower;
    }
    barrier(); // every subgroup's counts complete

    // Step 2: each invocation takes DIGITS_PER_INVOCATION consecutive digits.
    uint subgroups = gl_NumSubgroups;
    uint first_digit = lid * DIGITS_PER_INVOCATION;
    uint total = 0u;
    for (uint j = 0u; j < DIGITS_PER_INVOCATION; ++j) {
        uint d = first_digit + j;
        if (d < RADIX) {
            for (uint s = 0u; s < subgroups; ++s) total += sub_counts[s * RADIX + d];
        }
    }
    uint start = subgroupExclusiveAdd(total);
    if (lane == width - 1u) sub_sums[sub] = start + total;
    barrier();
    for (uint s = 0u; s < sub; ++s) start += sub_sums[s];
    for (uint j = 0u; j < DIGITS_PER_INVOCATION; ++j) {
        uint d = first_digit + j;
        if (d < RADIX) {
            digit_out[d] = hist[d * tiles + g] - start;
            for (uint s = 0u; s < subgroups; ++s) {
                uint c = sub_counts[s * RADIX + d];
                sub_counts[s * RADIX + d] = start;
                start += c;
            }
        }
    }
    barrier();

    // Step 3: the local sort.
    for (uint r = 0u; r < KEYS; ++r) {
        if (run + r * width < n) {
            uint digit = (key[r] >> pc.shift) & mask;
            uint pos = sub_counts[sub * RADIX + digit] + rank[r];
            tile_keys[pos] = key[r];
            if (values) tile_vals[pos] = val[r];
        }
    }
    barrier();

    // Step 4: coalesced writes of the tile's valid prefix.
    uint count = min(TILE, n - tile_base);
    for (uint r = 0u; r < KEYS; ++r) {
        uint j = r * WORKGROUP_SIZE + lid;
        if (j < count) {
            uint k = tile_keys[j];
            uint o = digit_out[(k >> pc.shift) & mask] + j;
            keys_out[o] = k;
            if (values) vals_out[o] = tile_vals[j];
        }
    }
}
