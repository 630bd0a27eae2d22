#version 460
// Shadow rays of the `shadow` integrator (PDACRT Table 2: one point light): from each
// primary hit towards the light. The unshadowed contribution — emission plus a Lambertian
// surface lit by the light, albedo/π · I · cos θ / d² — waits in `contribution` (2 vec4
// per pixel: emission, light) until the occlusion test says whether the light is
// visible. Missed primary rays get empty rays (tmax = 0 never hits).
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"
#include "material.glsl"

layout(push_constant) uniform Push { FrameParams frame; };
layout(std430, set = 0, binding = 0) readonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 1) readonly buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 2) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 3) readonly buffer TriMaterial { uint triangle_material[]; };
layout(std430, set = 0, binding = 4) readonly buffer Materials { Material materials[]; };
layout(std430, set = 0, binding = 5) writeonly buffer ShadowRays { Ray shadow_rays[]; };
layout(std430, set = 0, binding = 6) writeonly buffer Contribution { vec4 contribution[]; };

const float INV_PI = 0.31830988618379067;

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    Hit hit = hits[i];
    Ray primary = rays[i];
    if (hit.triangle == MISS) {
        shadow_rays[i] = Ray(primary.origin, 0.0, primary.dir, 0.0);
        contribution[2u * i] = vec4(0.0);
        contribution[2u * i + 1u] = vec4(0.0);
        return;
    }
    Triangle tri = triangles[hit.triangle];
    vec3 n = normalize(cross(tri.e1.xyz, tri.e2.xyz));
    if (dot(n, primary.dir) > 0.0) n = -n;
    vec3 p = primary.origin + hit.t * primary.dir + frame.ray_epsilon * n;
    vec3 to_light = frame.light.xyz - p;
    float d2 = max(dot(to_light, to_light), 1e-12);
    vec3 l = to_light * inversesqrt(d2);
    Material m = materials[triangle_material[hit.triangle]];
    float cos_l = dot(n, l);
    vec3 lit = cos_l > 0.0 ? m.diffuse.rgb * INV_PI * frame.light.w * cos_l / d2 : vec3(0.0);
    // A light behind the surface needs no ray: tmax = 0 never hits.
    shadow_rays[i] = Ray(p, 0.0, l, cos_l > 0.0 ? sqrt(d2) * (1.0 - 1e-4) : 0.0);
    contribution[2u * i] = vec4(m.emission.rgb, 0.0);
    contribution[2u * i + 1u] = vec4(lit, 0.0);
}
