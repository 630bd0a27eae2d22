#version 460
//! variant sum: MODE=0
//! variant count: MODE=1
//! variant argmin: MODE=2
// Reduce-by-key, barrier-free segment variant (CPU devices), pass 2 (heads = exclusive
// scan of rbk_seg_heads.comp's counts): every run belongs to the invocation whose
// segment holds its head, and that invocation reduces it to its end, past the segment
// if it runs on, so no run is split between invocations: no atomics, and the arg-min
// is one pass. Each invocation first skips the tail of a run that started before its
// segment. The segment holding the last key writes the number of runs.
// Every key read is guarded by an explicit branch, not by `&&`: a compiler may evaluate
// both sides of a side-effect-free `&&`, and keys[n] is past the buffer.
// MODE 0: out_a[s] = wrapping sum of in_a over the run;
// MODE 1: out_a[s] = the run's length;
// MODE 2: out_a[s] = the smallest in_a as f32 by total order (f32_order), out_b[s] = its
//         in_b (the smaller id on ties).
#include "grid.glsl"
#include "prim.glsl"
layout(constant_id = 1) const uint ITEMS = 2048;
layout(std430, set = 0, binding = 0) readonly buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 2) readonly buffer Heads { uint heads[]; };
layout(std430, set = 0, binding = 3) readonly buffer InA { uint in_a[]; };
layout(std430, set = 0, binding = 4) readonly buffer InB { uint in_b[]; };
layout(std430, set = 0, binding = 5) writeonly buffer OutKeys { uint out_keys[]; };
layout(std430, set = 0, binding = 6) writeonly buffer OutA { uint out_a[]; };
layout(std430, set = 0, binding = 7) writeonly buffer OutB { uint out_b[]; };
layout(std430, set = 0, binding = 8) writeonly buffer Count { uint count[]; };

void main() {
    if (linear_group_id() >= hdr[HDR_GROUPS + 1u]) return;
    uint seg = linear_invocation_id();
    if (seg >= hdr[HDR_GROUPS]) return;
    uint n = hdr[HDR_N];
    uint begin = seg * ITEMS;
    uint end = min(begin + ITEMS, n);
    uint s = heads[seg];
    uint i = begin;
    if (begin > 0u) {
        uint before = keys[begin - 1u];
        for (; i < end; ++i) {
            if (keys[i] != before) break;
        }
    }
    while (i < end) {
        uint k = keys[i];
        uint j = i + 1u;
#if MODE == 0
        uint acc = in_a[i];
        for (; j < n; ++j) {
            if (keys[j] != k) break;
            acc += in_a[j];
        }
        out_a[s] = acc;
#elif MODE == 1
        for (; j < n; ++j) {
            if (keys[j] != k) break;
        }
        out_a[s] = j - i;
#else
        uint best = f32_order(in_a[i]);
        uint id = in_b[i];
        for (; j < n; ++j) {
            if (keys[j] != k) break;
            uint o = f32_order(in_a[j]);
            uint b = in_b[j];
            if (o < best || (o == best && b < id)) {
                best = o;
                id = b;
            }
        }
        out_a[s] = f32_unorder(best);
        out_b[s] = id;
#endif
        out_keys[s] = k;
        ++s;
        i = j;
    }
    if (end == n) count[0] = s;
}
