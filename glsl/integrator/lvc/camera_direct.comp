#version 460
// Camera pass, stream 0 (Algorithm 8, line 6): direct lighting, technique s = 1 — a fresh
// light sample connected to the camera vertex (src/bidir/connect.rs
// `Connector::light_sample`), MIS-weighted, and its shadow ray. Writes slot i of the
// shadow rays and contributions, and clears the padding slots n .. P.base before the
// connections' (their region starts at a storage-buffer offset the device can bind).
#include "grid.glsl"
#include "geometry.glsl"
#include "random.glsl"
#include "bsdf.glsl"
#include "../pt/pt.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push {
    LvcPush P;
    BUFFER_REF(LvcConstantsInRef, constants)
    BUFFER_REF(UintsInRef, live_ids)
    BUFFER_REF(UintsInRef, order)
    BUFFER_REF(LvcVerticesInRef, vertices)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(BsdfsInRef, bsdfs)
    BUFFER_REF(LightsInRef, lights)
    BUFFER_REF(FloatsInRef, light_cdf)
    BUFFER_REF(RaysOutRef, shadow_rays)
    BUFFER_REF(ContributionsOutRef, contrib)
};
BUFFER_BINDING(0, readonly, LvcConstants, constants)
BUFFER_BINDING(1, readonly, uint, live_ids)
BUFFER_BINDING(2, readonly, uint, order)
BUFFER_BINDING(3, readonly, LvcVertex, vertices)
BUFFER_BINDING(4, readonly, Triangle, triangles)
BUFFER_BINDING(5, readonly, BsdfParams, bsdfs)
BUFFER_BINDING(6, readonly, Light, lights)
BUFFER_BINDING(7, readonly, float, light_cdf)
BUFFER_BINDING(8, writeonly, Ray, shadow_rays)
BUFFER_BINDING(9, writeonly, Contribution, contrib)
#define C constants.data[0]

#include "lvc_surface.glsl"
#include "lvc_lights.glsl"
#include "lvc_bsdf.glsl"

void main() {
    uint jj = linear_invocation_id();
    if (jj >= P.base) return;
    if (jj >= P.active_count) {
        shadow_rays.data[jj] = no_ray();
        contrib.data[jj] = Contribution(vec3(0.0), CONTRIBUTION_NONE, 0.0, CONTRIBUTION_NONE, 0u, 0u);
        return;
    }
    uint i = (C.flags & LVC_FLAG_SORTED) != 0u ? order.data[jj] : jj;
    shadow_rays.data[i] = no_ray();
    contrib.data[i] = Contribution(vec3(0.0), CONTRIBUTION_NONE, 0.0, CONTRIBUTION_NONE, 0u, 0u);
    LvcVertex z = vertices.data[i];
    uint j = z.depth;
    uint need = VERTEX_VALID | VERTEX_CONNECTIBLE;
    if ((z.flags & need) != need || !(C.count_light_sample > 0.0) || !depth_allows(C, j + 1u))
        return;
    uint c = live_ids.data[i];
    uint pixel = P.pixel_offset + c % P.pixel_count;
    uint pass = P.first_pass + c / P.pixel_count;
    vec3 u = vec3(random01(pixel, pass, camera_dim(j, DIM_LIGHT_PICK), C.seed),
                  random01(pixel, pass, camera_dim(j, DIM_LIGHT_POINT), C.seed),
                  random01(pixel, pass, camera_dim(j, DIM_LIGHT_POINT + 1u), C.seed));
    LightPoint q = lvc_sample_light(u, C.light_count);
    if (!q.valid) return;
    vec3 to = q.p - z.p;
    float dist2 = dot(to, to);
    if (!(dist2 > 0.0)) return;
    vec3 dir = to / sqrt(dist2);
    float cos_light = abs_cos(q.n, dir);
    vec3 le = (q.delta || dot(q.n, -dir) > 0.0) ? q.radiance : vec3(0.0);
    vec3 ng = triangle_normal(z.triangle);
    Endpoint e = endpoint_eval(z, ng, dir, TRANSPORT_RADIANCE);
    vec3 value = z.beta * e.f * le * (cos_light / (dist2 * q.pdf_area));
    if (value == vec3(0.0)) return;
    float emit_dir = q.delta ? uniform_sphere_pdf() : cos_light * LVC_INV_PI;
    float light_rev = q.delta ? 0.0 : e.pdf_fwd * cos_light / dist2;
    float camera_fwd = emit_dir * abs_cos(ng, dir) / dist2;
    float camera_partial = mis_partial(z, count_camera_vertex(C, j, false), e.pdf_rev);
    float others = C.count_emitter_hit * light_rev + q.pdf_area * camera_fwd * camera_partial;
    float weight = mis_balance(others / (C.count_light_sample * q.pdf_area));
    Ray r;
    if (!shadow_ray(z.p, ng, q.p, q.n, C.ray_epsilon, r)) return;
    shadow_rays.data[i] = r;
    contrib.data[i] = Contribution(value * weight, technique_code(1u, j + 1u), weight,
                                   CONTRIBUTION_NONE, 0u, 0u);
}
