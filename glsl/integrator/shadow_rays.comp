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

layout(push_constant) uniform Push {
    FrameParams frame;
    BUFFER_REF(RaysInRef, rays)
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(UintsInRef, triangle_material)
    BUFFER_REF(MaterialsInRef, materials)
    BUFFER_REF(RaysOutRef, shadow_rays)
    BUFFER_REF(Vec4sOutRef, contribution)
};
BUFFER_BINDING(0, readonly, Ray, rays)
BUFFER_BINDING(1, readonly, Hit, hits)
BUFFER_BINDING(2, readonly, Triangle, triangles)
BUFFER_BINDING(3, readonly, uint, triangle_material)
BUFFER_BINDING(4, readonly, Material, materials)
BUFFER_BINDING(5, writeonly, Ray, shadow_rays)
BUFFER_BINDING(6, writeonly, vec4, contribution)

const float INV_PI = 0.31830988618379067;

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    Hit hit = hits.data[i];
    Ray primary = rays.data[i];
    if (hit.triangle == MISS) {
        shadow_rays.data[i] = Ray(primary.origin, 0.0, primary.dir, 0.0);
        contribution.data[2u * i] = vec4(0.0);
        contribution.data[2u * i + 1u] = vec4(0.0);
        return;
    }
    Triangle tri = triangles.data[hit.triangle];
    vec3 n = normalize(triangle_normal(tri));
    if (dot(n, primary.dir) > 0.0) n = -n;
    vec3 p = primary.origin + hit.t * primary.dir + frame.ray_epsilon * n;
    vec3 to_light = frame.light.xyz - p;
    float d2 = max(dot(to_light, to_light), 1e-12);
    vec3 l = to_light * inversesqrt(d2);
    Material m = materials.data[triangle_material.data[hit.triangle]];
    float cos_l = dot(n, l);
    vec3 lit = cos_l > 0.0 ? m.diffuse.rgb * INV_PI * frame.light.w * cos_l / d2 : vec3(0.0);
    // A light behind the surface needs no ray: tmax = 0 never hits.
    shadow_rays.data[i] = Ray(p, 0.0, l, cos_l > 0.0 ? sqrt(d2) * (1.0 - 1e-4) : 0.0);
    contribution.data[2u * i] = vec4(m.emission.rgb, 0.0);
    contribution.data[2u * i + 1u] = vec4(lit, 0.0);
}
