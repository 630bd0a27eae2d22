#version 460
// Hit records from the global closest-hit arrays: PDACRT tracks t and the triangle
// (mints and hitid); the barycentrics come from one more test against the winner, with
// the same arithmetic, so t is reproduced exactly. In place: each ray's packed closest
// hit sits in the first half of its own hit record (BEST_SLOT in pdacrt.glsl), which
// only this invocation reads and then overwrites.
#include "grid.glsl"
#include "geometry.glsl"
#include "pdacrt.glsl"

struct FinalizePush {
    uint n;
    uint ray_offset;
};
layout(push_constant) uniform Push {
    FinalizePush pc;
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(RaysInRef, rays)
    BUFFER_REF(HitsRef, hits)
};
BUFFER_BINDING(0, readonly, Triangle, triangles)
BUFFER_BINDING(1, readonly, Ray, rays)
BUFFER_BINDING(2, , Hit, hits)
// The hit records' first halves, holding the packed closest hits (BEST_SLOT).
#ifdef SPLITRAY_DESCRIPTORS
layout(std430, set = 0, binding = 2) buffer Best { uvec2 data[]; } best;
#else
#define best Uvec2sRef(uvec2(hits))
#endif

void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    uvec2 closest = best.data[BEST_SLOT(pc.ray_offset + i)];
    uint tri = closest.x;
    Hit h = Hit(1.0 / 0.0, MISS, 0.0, 0.0);
    if (tri != MISS) {
        Ray r = rays.data[pc.ray_offset + i];
        Triangle t = triangles.data[tri];
        float u, v;
        intersect_triangle(r.origin, r.dir, r.tmin, 1.0 / 0.0, t.v0.xyz, t.v1.xyz, t.v2.xyz, u, v);
        h = Hit(hit_t(closest), tri, u, v);
    }
    hits.data[pc.ray_offset + i] = h;
}
