#version 460
// Global closest-hit update, Algorithm 1 line 9: each ray's minimum over this flush
// (one run per ray after the segmented arg-min) replaces the global one when closer, or
// equally close with a smaller triangle index.
#include "grid.glsl"
#include "geometry.glsl"
#include "pdacrt.glsl"

layout(std430, set = 0, binding = 0) readonly buffer RunRays { uint run_rays[]; };
layout(std430, set = 0, binding = 1) readonly buffer RunT { float run_t[]; };
layout(std430, set = 0, binding = 2) readonly buffer RunTri { uint run_tri[]; };
layout(std430, set = 0, binding = 3) readonly buffer RunTotal { uint run_total; };
// The hit buffer, holding the closest hits so far (BEST_SLOT in pdacrt.glsl).
layout(std430, set = 0, binding = 4) buffer Best { uvec2 best[]; };
layout(push_constant) uniform Push { uint max_runs; uint ray_offset; } pc;

void main() {
    uint i = linear_invocation_id();
    if (i >= min(run_total, pc.max_runs)) return;
    uint ray = run_rays[i];
    float t = run_t[i];
    uint tri = run_tri[i];
    if (tri == MISS) return;
    // One run per ray: no other invocation touches this ray's record. Compared as the
    // packed (ordered t, triangle) pair, the order of the atomic flush.
    uint slot = BEST_SLOT(pc.ray_offset + ray);
    uvec2 old = best[slot];
    uvec2 candidate = uvec2(tri, ordered_bits(t));
    if (candidate.y < old.y || (candidate.y == old.y && candidate.x < old.x)) {
        best[slot] = candidate;
    }
}
