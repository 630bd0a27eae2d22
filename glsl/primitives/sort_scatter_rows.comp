#version 460
// Radix sort pass, step 3, subgroup-row variant (the workgroup must be exactly one
// subgroup: subgroup barriers then order its shared-memory traffic). The tile is read
// in rows of WORKGROUP_SIZE consecutive keys (coalesced). Within a row, each key's rank
// among equal digits to its left comes from the row's digits broadcast through shared
// memory; the last key of each digit advances that digit's running offset. Stable: rows
// in order, lanes in order within a row. Same tiles, bindings and push constants as
// sort_scatter.comp, which it replaces on CPU devices.
#extension GL_KHR_shader_subgroup_basic : require
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint KEYS = 64;
layout(constant_id = 2) const uint RADIX_BITS = 8;
const uint RADIX = 1u << RADIX_BITS;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, set = 0, binding = 2) readonly buffer ValsIn { uint vals_in[]; };
layout(std430, set = 0, binding = 3) readonly buffer Hist { uint hist[]; };
layout(std430, set = 0, binding = 4) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, set = 0, binding = 5) writeonly buffer ValsOut { uint vals_out[]; };
layout(std430, set = 0, binding = 6) readonly buffer LaneCounts { uint lane_counts[]; }; // unused here
layout(push_constant) uniform Push { uint shift; uint bits; uint flags; } pc; // bit 0: values

shared uint cnt[RADIX];
shared uint row_d[2 * WORKGROUP_SIZE];

void sync() {
    subgroupMemoryBarrierShared();
    subgroupBarrier();
}

void main() {
    uint g = linear_group_id();
    uint tiles = hdr[HDR_GROUPS + 1u];
    if (g >= tiles) return;
    uint n = hdr[HDR_N];
    uint lid = gl_LocalInvocationID.x;
    for (uint d = lid; d < RADIX; d += WORKGROUP_SIZE) cnt[d] = hist[d * tiles + g];
    sync();
    uint mask = (1u << pc.bits) - 1u;
    bool values = (pc.flags & 1u) != 0u;
    uint base = g * WORKGROUP_SIZE * KEYS;
    for (uint r = 0u; r < KEYS; ++r) {
        uint row = base + r * WORKGROUP_SIZE;
        if (row >= n) break;
        uint i = row + lid;
        bool valid = i < n;
        uint k = valid ? keys_in[i] : 0u;
        uint d = valid ? (k >> pc.shift) & mask : 0xFFFFFFFFu;
        uint slot = (r & 1u) * WORKGROUP_SIZE;
        row_d[slot + lid] = d;
        sync();
        uint rank = 0u;
        bool last = true;
        for (uint w = 0u; w < WORKGROUP_SIZE; ++w) {
            bool same = row_d[slot + w] == d;
            rank += (same && w < lid) ? 1u : 0u;
            last = last && !(same && w > lid);
        }
        uint pos = valid ? cnt[d] + rank : 0u;
        sync();
        if (valid) {
            keys_out[pos] = k;
            if (values) vals_out[pos] = vals_in[i];
            if (last) cnt[d] = pos + 1u;
        }
        sync();
    }
}
