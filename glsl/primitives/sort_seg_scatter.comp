#version 460
//! variant first: FIXED_FLAGS=9
//! variant middle: FIXED_FLAGS=13
//! variant last: FIXED_FLAGS=5
//! variant first64: FIXED_FLAGS=9 WIDE64=1
//! variant middle64: FIXED_FLAGS=13 WIDE64=1
#ifdef WIDE64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif
// Radix sort pass, step 3, barrier-free segment variant (pairs with
// sort_seg_count.comp). Each invocation loads the scanned offsets of its own segment
// (hist[digit * segments + segment]) into its own column of shared counters and writes
// its keys (and values) in their original order: stable, with no barrier and no
// cooperation inside the workgroup. Keys and values are read as uvec4s (KEYS a multiple
// of 4), or as u64vec4s with the `...64` variants (KEYS a multiple of 8).
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
layout(std430, set = 0, binding = 4) writeonly buffer PairsOut { uvec2 pairs_out[]; };
layout(std430, set = 0, binding = 5) writeonly buffer ValsOut { uint vals_out[]; };
#ifdef WIDE64
// `wide64` (Tuning::wide_accesses): pairs read four per u64vec4 and written as one
// 64-bit component each, half the per-lane accesses on lavapipe. Same memory layout
// as the uvec2 pairs (key in the low half).
layout(std430, set = 0, binding = 1) readonly buffer PairsIn8 { u64vec4 pairs_in8[]; };
layout(std430, set = 0, binding = 1) readonly buffer KeysIn8 { u64vec4 keys_in8[]; };
layout(std430, set = 0, binding = 2) readonly buffer ValsIn8 { u64vec4 vals_in8[]; };
layout(std430, set = 0, binding = 4) writeonly buffer PairsOut64 { uint64_t pairs_out64[]; };
#endif
// flags bit 0: values; bit 2: the input is interleaved (key, value) pairs at binding 1;
// bit 3: write interleaved pairs to binding 4 (one uvec2 store per key instead of two
// scalar stores, and half the output streams). Bits 2 and 3 need bit 0.
layout(push_constant) uniform Push { uint shift; uint bits; uint flags; } pc;
#ifdef FIXED_FLAGS
// The pass kind fixed at compile time (the key-value pair passes: first 1|8, middle
// 1|4|8, last 1|4), so the branches on it fold away.
const uint FLAGS = FIXED_FLAGS;
#else
#define FLAGS pc.flags
#endif

shared uint counts[RADIX * WORKGROUP_SIZE];

// Output positions of four keys with counter indices `d`, in order (stable), and the
// counters advanced past them (earlier_equal in prim.glsl).
uvec4 take4(uvec4 d) {
    uvec4 pos = uvec4(counts[d.x], counts[d.y], counts[d.z], counts[d.w]) + earlier_equal(d);
    counts[d.x] = pos.x + 1u;
    counts[d.y] = pos.y + 1u;
    counts[d.z] = pos.z + 1u;
    counts[d.w] = pos.w + 1u;
    return pos;
}

// Writes four keys and their values, in order, to their places (pairs or arrays).
void place4(uvec4 k, uvec4 v, uint mask, uint lid, bool to_pairs) {
    uvec4 pos = take4(((k >> pc.shift) & mask) * WORKGROUP_SIZE + lid);
    for (uint c = 0u; c < 4u; ++c) {
        if (to_pairs) {
#ifdef WIDE64
            pairs_out64[pos[c]] = uint64_t(k[c]) | (uint64_t(v[c]) << 32);
#else
            pairs_out[pos[c]] = uvec2(k[c], v[c]);
#endif
        } else {
            keys_out[pos[c]] = k[c];
            vals_out[pos[c]] = v[c];
        }
    }
}

void main() {
    uint g = linear_group_id();
    uint tiles = hdr[HDR_GROUPS + 1u];
    if (g >= tiles) return;
    uint n = hdr[HDR_N];
    // A one-invocation workgroup never names its invocation, so that the whole kernel
    // stays uniform: lavapipe then runs it as scalar code with scalar memory accesses.
    uint lid = WORKGROUP_SIZE == 1u ? 0u : gl_LocalInvocationID.x;
    uint segments = tiles * WORKGROUP_SIZE;
    uint seg = g * WORKGROUP_SIZE + lid;
    uint begin = min(seg * KEYS, n);
    uint end = min(begin + KEYS, n);
    if (begin == end) return;
    for (uint d = 0u; d < RADIX; ++d) counts[d * WORKGROUP_SIZE + lid] = hist[d * segments + seg];
    uint mask = (1u << pc.bits) - 1u;
    bool values = (FLAGS & 1u) != 0u;
    uint i = begin;
    bool pairs_in = (FLAGS & 4u) != 0u;
    bool to_pairs = (FLAGS & 8u) != 0u;
    if (pairs_in || to_pairs) {
#ifdef WIDE64
        if (!pairs_in) {
            // Eight keys and eight values per pair of u64vec4s (begin is a multiple of
            // 8): each u64vec4 holds items 2j in its low halves and 2j + 1 in its high.
            for (; i + 8u <= end; i += 8u) {
                u64vec4 kw = keys_in8[i / 8u];
                u64vec4 vw = vals_in8[i / 8u];
                uvec4 klo = uvec4(kw), khi = uvec4(kw >> 32);
                uvec4 vlo = uvec4(vw), vhi = uvec4(vw >> 32);
                place4(uvec4(klo.x, khi.x, klo.y, khi.y), uvec4(vlo.x, vhi.x, vlo.y, vhi.y),
                       mask, lid, to_pairs);
                place4(uvec4(klo.z, khi.z, klo.w, khi.w), uvec4(vlo.z, vhi.z, vlo.w, vhi.w),
                       mask, lid, to_pairs);
            }
        }
#endif
        for (; i + 4u <= end; i += 4u) {
            uvec4 k, v;
            if (pairs_in) {
#ifdef WIDE64
                u64vec4 p = pairs_in8[i / 4u];
                k = uvec4(p);
                v = uvec4(p >> 32);
#else
                uvec4 p0 = keys_in4[i / 2u];
                uvec4 p1 = keys_in4[i / 2u + 1u];
                k = uvec4(p0.xz, p1.xz);
                v = uvec4(p0.yw, p1.yw);
#endif
            } else {
                k = keys_in4[i / 4u];
                v = vals_in4[i / 4u];
            }
            place4(k, v, mask, lid, to_pairs);
        }
        for (; i < end; ++i) {
            uint k = pairs_in ? keys_in[2u * i] : keys_in[i];
            uint v = pairs_in ? keys_in[2u * i + 1u] : vals_in[i];
            uint d = ((k >> pc.shift) & mask) * WORKGROUP_SIZE + lid;
            uint pos = counts[d];
            counts[d] = pos + 1u;
            if (to_pairs) {
                pairs_out[pos] = uvec2(k, v);
            } else {
                keys_out[pos] = k;
                vals_out[pos] = v;
            }
        }
        return;
    }
    if (values) {
        for (; i + 4u <= end; i += 4u) {
            uvec4 k = keys_in4[i / 4u];
            uvec4 v = vals_in4[i / 4u];
            uvec4 pos = take4(((k >> pc.shift) & mask) * WORKGROUP_SIZE + lid);
            for (uint c = 0u; c < 4u; ++c) {
                keys_out[pos[c]] = k[c];
                vals_out[pos[c]] = v[c];
            }
        }
    } else {
        for (; i + 4u <= end; i += 4u) {
            uvec4 k = keys_in4[i / 4u];
            uvec4 pos = take4(((k >> pc.shift) & mask) * WORKGROUP_SIZE + lid);
            for (uint c = 0u; c < 4u; ++c) keys_out[pos[c]] = k[c];
        }
    }
    for (; i < end; ++i) {
        uint k = keys_in[i];
        uint d = ((k >> pc.shift) & mask) * WORKGROUP_SIZE + lid;
        uint pos = counts[d];
        counts[d] = pos + 1u;
        keys_out[pos] = k;
        if (values) vals_out[pos] = vals_in[i];
    }
}
