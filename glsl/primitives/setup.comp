#version 460
// One invocation: reads n (from the push constants or a GPU count buffer), clamps it to
// the capacity and writes the header (n and folded indirect dispatch arguments per kind).
#include "grid.glsl"
#include "prim.glsl"
layout(std430, set = 0, binding = 0) readonly buffer Count { uint count_src[]; };
layout(std430, set = 0, binding = 1) buffer Hdr { uint hdr[]; };
layout(std430, set = 0, binding = 2) buffer Out { uint out_word[]; };
layout(push_constant) uniform Push {
    uint n;          // host count (flags bit 0 clear)
    uint count_word; // word index of the count in count_src (flags bit 0 set)
    uint flags;      // bit 0: read the count on the GPU; bit 1: write 0 to out_word[0]
    uint max_n;      // capacity of the scratch: n is clamped to it
    uint mul;        // the GPU count is multiplied by this
    uint max_x;      // maxComputeWorkGroupCount[0]
    uint items0;     // items per workgroup of dispatch kind 0..3 (0 = unused)
    uint items1;
    uint items2;
    uint items3;
} pc;

void write_args(uint k, uint items, uint n) {
    uint groups = items == 0u ? 0u : n / items + ((n % items) != 0u ? 1u : 0u);
    uint x = groups;
    uint y = 1u;
    if (groups > pc.max_x) {
        y = (groups + pc.max_x - 1u) / pc.max_x;
        x = (groups + y - 1u) / y;
    }
    hdr[HDR_GROUPS + k] = groups;
    hdr[8u + 4u * k] = x;
    hdr[9u + 4u * k] = y;
    hdr[10u + 4u * k] = 1u;
    hdr[11u + 4u * k] = 0u;
}

void main() {
    if (gl_GlobalInvocationID.x != 0u) return;
    uint n = (pc.flags & 1u) != 0u ? count_src[pc.count_word] * pc.mul : pc.n;
    n = min(n, pc.max_n);
    hdr[HDR_N] = n;
    write_args(0u, pc.items0, n);
    write_args(1u, pc.items1, n);
    write_args(2u, pc.items2, n);
    write_args(3u, pc.items3, n);
    if ((pc.flags & 2u) != 0u) out_word[0] = 0u;
}
