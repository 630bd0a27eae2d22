#version 460
// CBPT visibility, step 1 of 2: the shadow ray of every linking segment of the batch
// (camera-vertex major: segment = c · V_L + l), built from the thread index as
// src/bidir/scene.rs `shadow_ray` builds it — each end on a surface moved off it
// towards the other, the ray stopping just short of the far end. A segment whose ends
// coincide gets a ray that tests nothing (tmax 0), which visibility_pack counts
// occluded. The tracer then answers occlusion queries for these rays.
#include "grid.glsl"
#include "geometry.glsl"
#include "cbpt.glsl"

layout(push_constant) uniform Push { CbptPush pc; };
layout(std430, set = 0, binding = 0) readonly buffer Camera { CbptVertex camera[]; };
layout(std430, set = 0, binding = 1) readonly buffer Light { CbptVertex light[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Rays { Ray rays[]; };

// p moved off its surface (normal ng) to the side dir points to; a point in space
// (ng zero) stays.
vec3 offset_point(vec3 p, vec3 ng, vec3 dir) {
    if (ng == vec3(0.0)) return p;
    float eps = cbpt_dot(ng, dir) > 0.0 ? pc.ray_epsilon : -pc.ray_epsilon;
    precise vec3 moved = p + ng * eps;
    return moved;
}

void main() {
    uint i = linear_invocation_id();
    if (i >= pc.count) return;
    uint segment = pc.first + i;
    uint c = segment / pc.inner;
    CbptVertex z = camera[c];
    CbptVertex y = light[segment - c * pc.inner];
    precise vec3 dir = y.p - z.p;
    vec3 from = offset_point(z.p, z.ng, dir);
    vec3 to = offset_point(y.p, y.ng, -dir);
    precise vec3 d = to - from;
    precise float reach = sqrt(cbpt_dot(d, d));
    if (!(reach > 0.0)) {
        rays[i] = Ray(z.p, 0.0, vec3(0.0, 0.0, 1.0), 0.0);
        return;
    }
    precise vec3 unit = d / reach;
    precise float tmax = reach * pc.shadow_reach;
    rays[i] = Ray(from, 0.0, unit, tmax);
}
