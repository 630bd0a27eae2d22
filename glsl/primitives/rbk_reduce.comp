#version 460
// Reduce-by-key, pass 3: each invocation walks ITEMS contiguous items, reduces runs of
// equal segment ids locally and issues one atomic per run piece, so long runs cost one
// atomic per invocation, not per item.
// mode 0: out_a[s] += a[i]            (sum)
// mode 1: out_a[s] += 1               (run lengths)
// mode 2: out_a[s] = min(order(a[i])) (arg-min, step 1: smallest t as ordered bits)
// mode 3: out_b[s] = min(b[i]) over i with order(a[i]) == out_a[s] (step 2: its id)
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 16;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Seg { uint seg[]; };
layout(std430, set = 0, binding = 2) readonly buffer InA { uint in_a[]; };
layout(std430, set = 0, binding = 3) readonly buffer InB { uint in_b[]; };
layout(std430, set = 0, binding = 4) buffer OutA { uint out_a[]; };
layout(std430, set = 0, binding = 5) buffer OutB { uint out_b[]; };
layout(push_constant) uniform Push { uint mode; } pc;

void flush(uint s, uint acc) {
    if (pc.mode == 0u || pc.mode == 1u) {
        if (acc != 0u) atomicAdd(out_a[s], acc);
    } else if (pc.mode == 2u) {
        atomicMin(out_a[s], acc);
    } else {
        if (acc != 0xFFFFFFFFu) atomicMin(out_b[s], acc);
    }
}

void main() {
    uint g = linear_group_id();
    if (g >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint begin = min(g * WORKGROUP_SIZE * ITEMS + gl_LocalInvocationID.x * ITEMS, n);
    uint end = min(begin + ITEMS, n);
    if (begin >= end) return;
    uint mode = pc.mode;
    uint identity = mode >= 2u ? 0xFFFFFFFFu : 0u;
    uint cur = seg[begin] - 1u;
    uint acc = identity;
    uint best = mode == 3u ? out_a[cur] : 0u;
    for (uint i = begin; i < end; ++i) {
        uint s = seg[i] - 1u;
        if (s != cur) {
            flush(cur, acc);
            cur = s;
            acc = identity;
            if (mode == 3u) best = out_a[cur];
        }
        if (mode == 0u) {
            acc += in_a[i];
        } else if (mode == 1u) {
            acc += 1u;
        } else if (mode == 2u) {
            acc = min(acc, f32_order(in_a[i]));
        } else if (f32_order(in_a[i]) == best) {
            acc = min(acc, in_b[i]);
        }
    }
    flush(cur, acc);
}
