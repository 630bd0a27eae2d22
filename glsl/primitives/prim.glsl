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

#endif
