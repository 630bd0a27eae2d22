#version 460
// Mirror rays of the `reflection` integrator (PDACRT Table 2: one perfect specular
// bounce): every surface is a mirror; the reflected ray leaves the primary hit. Missed
// primary rays get empty rays.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"

layout(push_constant) uniform Push { FrameParams frame; };
layout(std430, set = 0, binding = 0) readonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 1) readonly buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 2) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Reflected { Ray reflected[]; };

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    Hit hit = hits[i];
    Ray primary = rays[i];
    if (hit.triangle == MISS) {
        reflected[i] = Ray(primary.origin, 0.0, primary.dir, 0.0);
        return;
    }
    Triangle tri = triangles[hit.triangle];
    vec3 n = normalize(cross(tri.e1.xyz, tri.e2.xyz));
    if (dot(n, primary.dir) > 0.0) n = -n;
    vec3 p = primary.origin + hit.t * primary.dir + frame.ray_epsilon * n;
    reflected[i] = Ray(p, 0.0, normalize(reflect(primary.dir, n)), 1.0 / 0.0);
}
