#version 460
// Hit records from the global closest-hit arrays: PDACRT tracks t and the triangle
// (mints and hitid); the barycentrics come from one more test against the winner, with
// the same arithmetic, so t is reproduced exactly. In place: each ray's packed closest
// hit sits in the first half of its own hit record (BEST_SLOT in pdacrt.glsl), which
// only this invocation reads and then overwrites.
#include "grid.glsl"
#include "geometry.glsl"
#include "pdacrt.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 1) readonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 2) buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 2) buffer Best { uvec2 best[]; };
layout(push_constant) uniform Push { uint n; uint ray_offset; } pc;

void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    uvec2 closest = best[BEST_SLOT(pc.ray_offset + i)];
    uint tri = closest.x;
    Hit h = Hit(1.0 / 0.0, MISS, 0.0, 0.0);
    if (tri != MISS) {
        Ray r = rays[pc.ray_offset + i];
        Triangle t = triangles[tri];
        float u, v;
        intersect_triangle(r.origin, r.dir, r.tmin, 1.0 / 0.0, t.v0.xyz, t.e1.xyz, t.e2.xyz, u, v);
        h = Hit(hit_t(closest), tri, u, v);
    }
    hits[pc.ray_offset + i] = h;
}
