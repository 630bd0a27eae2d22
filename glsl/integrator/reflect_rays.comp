#version 460
// Mirror rays of the `reflection` integrator (PDACRT Table 2: one perfect specular
// bounce): every surface is a mirror; the reflected ray leaves the primary hit. Missed
// primary rays get empty rays.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"

layout(push_constant) uniform Push {
    FrameParams frame;
    BUFFER_REF(RaysInRef, rays)
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(RaysOutRef, reflected)
};
BUFFER_BINDING(0, readonly, Ray, rays)
BUFFER_BINDING(1, readonly, Hit, hits)
BUFFER_BINDING(2, readonly, Triangle, triangles)
BUFFER_BINDING(3, writeonly, Ray, reflected)

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    Hit hit = hits.data[i];
    Ray primary = rays.data[i];
    if (hit.triangle == MISS) {
        reflected.data[i] = Ray(primary.origin, 0.0, primary.dir, 0.0);
        return;
    }
    Triangle tri = triangles.data[hit.triangle];
    vec3 n = normalize(triangle_normal(tri));
    if (dot(n, primary.dir) > 0.0) n = -n;
    vec3 p = primary.origin + hit.t * primary.dir + frame.ray_epsilon * n;
    reflected.data[i] = Ray(p, 0.0, normalize(reflect(primary.dir, n)), 1.0 / 0.0);
}
