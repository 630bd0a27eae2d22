// Per-tile counting for the ranked kernels (LevelSplit::PrefixSums; tiles in
// pdacrt.glsl): one workgroup per tile, its invocations' (left, right) counts combined
// through shared memory. One or two barriers per tile and no subgroup operations: not
// every device has subgroup arithmetic, and CPU devices pay for each barrier (lavapipe
// switches every invocation's context at one), so the first invocation does the
// combining alone: WORKGROUP_SIZE steps per tile of up to TILE_ITEMS elements.
#ifndef SPLITRAY_PDACRT_TILE_LANES_GLSL
#define SPLITRAY_PDACRT_TILE_LANES_GLSL

#include "grid.glsl"

shared uvec2 lane_counts[WORKGROUP_SIZE];

// The workgroup's sum of `mine`: valid in the first invocation only.
uvec2 tile_sum(uvec2 mine) {
    lane_counts[gl_LocalInvocationID.x] = mine;
    barrier();
    uvec2 total = uvec2(0u);
    if (gl_LocalInvocationID.x == 0u) {
        for (uint l = 0u; l < WORKGROUP_SIZE; ++l) total += lane_counts[l];
    }
    return total;
}

// The sum of `mine` over the invocations before this one in the workgroup.
uvec2 tile_exclusive_scan(uvec2 mine) {
    lane_counts[gl_LocalInvocationID.x] = mine;
    barrier();
    if (gl_LocalInvocationID.x == 0u) {
        uvec2 run = uvec2(0u);
        for (uint l = 0u; l < WORKGROUP_SIZE; ++l) {
            uvec2 count = lane_counts[l];
            lane_counts[l] = run;
            run += count;
        }
    }
    barrier();
    return lane_counts[gl_LocalInvocationID.x];
}

// The side flags of a status code: (belongs to the left child, to the right child).
uvec2 side_flags(uint code) {
    return uvec2(code == CODE_LEFT || code == CODE_BOTH, code == CODE_RIGHT || code == CODE_BOTH);
}

#endif
