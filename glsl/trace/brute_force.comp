#version 460
// Brute-force closest hit: every ray against every triangle.
//
// The correctness oracle behind `--tracer brute-force`. One invocation per ray; the
// workgroup stages BATCH triangles at a time through shared memory, so each pair of
// workgroup barriers is amortised over WORKGROUP_SIZE × BATCH ray–triangle tests (barriers
// are very slow on lavapipe, cheap on GPUs; both sizes are specialization constants).
// Ties in t go to the smaller triangle index, independent of batching.
// With OCCLUSION defined, a ray stops at its first hit (shadow rays): hits[i].triangle
// is then any blocker, and t its distance.
//! variant occlusion: OCCLUSION=1
#include "grid.glsl"
#include "geometry.glsl"

layout(constant_id = 1) const uint BATCH = 256;

struct BruteForcePush {
    uint ray_count;
    uint triangle_count;
};
layout(push_constant) uniform Push {
    BruteForcePush pc;
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(RaysInRef, rays)
    BUFFER_REF(HitsOutRef, hits)
};
BUFFER_BINDING(0, readonly, Triangle, triangles)
BUFFER_BINDING(1, readonly, Ray, rays)
BUFFER_BINDING(2, writeonly, Hit, hits)

shared Triangle staged[BATCH];

void main() {
    uint ray_index = linear_invocation_id();
    bool has_ray = ray_index < pc.ray_count;
    Ray ray;
    if (has_ray) ray = rays.data[ray_index];
    ShearedRay sheared = shear_ray(ray.origin, ray.dir);
    float best_t = 1.0 / 0.0;
    uint best_tri = MISS;
    float best_u = 0.0, best_v = 0.0;
    bool done = !has_ray;
    // An empty segment meets no triangle: it skips the tests but still takes part in the
    // workgroup's barriers.
    if (has_ray && ray_is_empty(ray)) done = true;

    for (uint base = 0; base < pc.triangle_count; base += BATCH) {
        uint count = min(BATCH, pc.triangle_count - base);
        for (uint j = gl_LocalInvocationID.x; j < count; j += WORKGROUP_SIZE) {
            staged[j] = triangles.data[base + j];
        }
        barrier();
        if (!done) {
            for (uint j = 0; j < count; ++j) {
                float u, v;
                float t = intersect_sheared(sheared, ray.tmin, min(ray.tmax, best_t),
                                            staged[j].v0.xyz, staged[j].v1.xyz, staged[j].v2.xyz, u, v);
                // Strictly closer only: the first (smallest-index) of equal-t hits stays.
                if (t < best_t) {
                    best_t = t;
                    best_tri = base + j;
                    best_u = u;
                    best_v = v;
#ifdef OCCLUSION
                    done = true;
                    break;
#endif
                }
            }
        }
        barrier();
    }
    if (has_ray) hits.data[ray_index] = Hit(best_t, best_tri, best_u, best_v);
}
