#version 460
// Global closest-hit update, Algorithm 1 line 9: each ray's minimum over this flush
// (one run per ray after the segmented arg-min) replaces the global one when closer, or
// equally close with a smaller triangle index.
#include "grid.glsl"
#include "geometry.glsl"
#include "pdacrt.glsl"

struct UpdateHitsPush {
    uint max_runs;
    uint ray_offset;
};
layout(push_constant) uniform Push {
    UpdateHitsPush pc;
    BUFFER_REF(UintsInRef, run_rays)
    BUFFER_REF(FloatsInRef, run_t)
    BUFFER_REF(UintsInRef, run_tri)
    BUFFER_REF(UintsInRef, run_total)  // one word
    // The hit buffer, holding the closest hits so far (BEST_SLOT in pdacrt.glsl).
    BUFFER_REF(Uvec2sRef, best)

};
BUFFER_BINDING(0, readonly, uint, run_rays)
BUFFER_BINDING(1, readonly, float, run_t)
BUFFER_BINDING(2, readonly, uint, run_tri)
BUFFER_BINDING(3, readonly, uint, run_total)
BUFFER_BINDING(4, , uvec2, best)

void main() {
    uint i = linear_invocation_id();
    if (i >= min(run_total.data[0], pc.max_runs)) return;
    uint ray = run_rays.data[i];
    float t = run_t.data[i];
    uint tri = run_tri.data[i];
    if (tri == MISS) return;
    // One run per ray: no other invocation touches this ray's record. Compared as the
    // packed (ordered t, triangle) pair, the order of the atomic flush.
    uint slot = BEST_SLOT(pc.ray_offset + ray);
    uvec2 old = best.data[slot];
    uvec2 candidate = uvec2(tri, ordered_bits(t));
    if (candidate.y < old.y || (candidate.y == old.y && candidate.x < old.x)) {
        best.data[slot] = candidate;
    }
}
