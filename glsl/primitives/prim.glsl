// Shared by the primitives' kernels: the scratch header that setup.comp fills.
//
// Word 0 holds n (clamped to the capacity); words 1..4 the workgroup count of each
// dispatch kind; words 8 + 4k .. 8 + 4k + 2 the (folded) indirect dispatch arguments of
// kind k. Kernels read n and their group count from here, never from push constants, so
// the host-known and GPU-known counts share one code path.
#ifndef SPLITRAY_PRIM_GLSL
#define SPLITRAY_PRIM_GLSL

#define HDR_N 0u
#define HDR_GROUPS 1u

// Order-preserving map of f32 bits to u32 (total order; -0 < +0).
uint f32_order(uint b) {
    return (b & 0x80000000u) != 0u ? ~b : (b | 0x80000000u);
}
uint f32_unorder(uint o) {
    return (o & 0x80000000u) != 0u ? (o & 0x7FFFFFFFu) : ~o;
}

// For four digits handled together (the sort's counters, four keys at a time): how many
// of the earlier ones in the quad equal each. The four counter loads can then be issued
// together and the four stores after them, instead of four dependent load-store pairs:
// the key at c takes counter + earlier_equal(d)[c], and storing that + 1 in quad order
// leaves each counter past its last key (the later store of a shared counter is the
// larger). On lavapipe, where every lane's shared-memory access is a scalar access,
// this took the 4M-pair sort from 71.6 to 67.0 ms and from 74.6 to 68.5 ms (two
// tuning sweeps, minima of 5 interleaved rounds); eight keys at a time measured 5%
// slower than four.
uvec4 earlier_equal(uvec4 d) {
    return uvec4(0u,
                 uint(d.y == d.x),
                 uint(d.z == d.x) + uint(d.z == d.y),
                 uint(d.w == d.x) + uint(d.w == d.y) + uint(d.w == d.z));
}

#endif
