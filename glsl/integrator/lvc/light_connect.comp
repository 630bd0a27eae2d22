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

layout(push_constant) uniform Push {
    LvcPush P;
    BUFFER_REF(LvcConstantsInRef, constants)
    BUFFER_REF(LvcVerticesInRef, cache)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(BsdfsInRef, bsdfs)
    BUFFER_REF(RaysOutRef, shadow_rays)
    BUFFER_REF(ContributionsOutRef, contrib)
};
BUFFER_BINDING(0, readonly, LvcConstants, constants)
BUFFER_BINDING(1, readonly, LvcVertex, cache)
BUFFER_BINDING(2, readonly, Triangle, triangles)
BUFFER_BINDING(3, readonly, BsdfParams, bsdfs)
BUFFER_BINDING(4, writeonly, Ray, shadow_rays)
BUFFER_BINDING(5, writeonly, Contribution, contrib)
#define C constants.data[0]

#include "lvc_surface.glsl"
#include "lvc_bsdf.glsl"

void main() {
    uint k = linear_invocation_id();
    if (k >= P.active_count) return;
    shadow_rays.data[k] = no_ray();
    contrib.data[k] = Contribution(vec3(0.0), CONTRIBUTION_NONE, 0.0, CONTRIBUTION_NONE, 0u, 0u);
    if (!(C.count_light_trace > 0.0)) return;
    LvcVertex y = cache.data[P.base + k];
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
    shadow_rays.data[k] = r;
    uint pass_in_chunk = y.path / C.light_paths;
    contrib.data[k] = Contribution(value * weight / float(C.light_paths),
                                   technique_code(y.depth + 1u, 1u), weight,
                                   pass_in_chunk * (C.width * C.height) + pixel, 0u, 0u);
}
