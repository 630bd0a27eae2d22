#version 460
// Light tracing (t = 1): cache vertex base + k connected to the pinhole
// (src/bidir/connect.rs `Connector::light_trace`): the pixel it projects to, its
// MIS-weighted contribution to that pixel's pass estimate (divided by the pass's light
// paths, since every light path of the pass is a sample of every pixel) and the shadow
// ray towards the camera. The splat waits for the shadow ray (splat.comp).
#include "grid.glsl"
#include "geometry.glsl"
#include "bsdf.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push { LvcPush P; };
layout(std430, set = 0, binding = 0) readonly buffer Constants { LvcConstants C; };
layout(std430, set = 0, binding = 1) readonly buffer Cache { LvcVertex cache[]; };
layout(std430, set = 0, binding = 2) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 3) readonly buffer Bsdfs { BsdfParams bsdfs[]; };
layout(std430, set = 0, binding = 4) writeonly buffer ShadowRays { Ray shadow_rays[]; };
layout(std430, set = 0, binding = 5) writeonly buffer Contributions { Contribution contrib[]; };

#include "lvc_surface.glsl"
#include "lvc_bsdf.glsl"

void main() {
    uint k = linear_invocation_id();
    if (k >= P.active_count) return;
    shadow_rays[k] = no_ray();
    contrib[k] = Contribution(vec3(0.0), CONTRIBUTION_NONE, 0.0, CONTRIBUTION_NONE, 0u, 0u);
    if (!(C.count_light_trace > 0.0)) return;
    LvcVertex y = cache[P.base + k];
    vec3 ng = triangle_normal(y.triangle);
    vec3 to = C.origin - y.p;
    float dist2 = dot(to, to);
    if (!(dist2 > 0.0)) return;
    vec3 dir = to / sqrt(dist2);
    uint pixel = camera_pixel_of(C, -dir);
    if (pixel == 0xFFFFFFFFu) return;
    float cos_cam = camera_cos(C, -dir);
    float camera_area = camera_pdf_direction(C, -dir) * abs_cos(ng, dir) / dist2;
    float we = camera_importance(C, -dir);
    Endpoint e = endpoint_eval(y, ng, dir, TRANSPORT_IMPORTANCE);
    float partial = mis_partial(y, count_light_vertex(C, y.depth), e.pdf_rev);
    float weight = mis_balance(camera_area * partial / C.count_light_trace);
    vec3 value = y.beta * e.f * (we * cos_cam / dist2);
    if (value == vec3(0.0)) return;
    Ray r;
    if (!shadow_ray(y.p, ng, C.origin, vec3(0.0), C.ray_epsilon, r)) return;
    shadow_rays[k] = r;
    uint pass_in_chunk = y.path / C.light_paths;
    contrib[k] = Contribution(value * weight / float(C.light_paths),
                              technique_code(y.depth + 1u, 1u), weight,
                              pass_in_chunk * (C.width * C.height) + pixel, 0u, 0u);
}
