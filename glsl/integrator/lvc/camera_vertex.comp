#version 460
// Camera pass, after the trace (and the material sort): the vertex each live camera
// path reached (its record for the three kernels that follow) and technique s = 0, the
// emitter it may lie on, MIS-weighted (src/bidir/connect.rs `Connector::emitter_hit`).
#include "grid.glsl"
#include "geometry.glsl"
#include "random.glsl"
#include "bsdf.glsl"
#include "../pt/pt.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push { LvcPush P; };
layout(std430, set = 0, binding = 0) readonly buffer Constants { LvcConstants C; };
layout(std430, set = 0, binding = 1) readonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 2) readonly buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 3) readonly buffer Active { uint live_ids[]; };
layout(std430, set = 0, binding = 4) readonly buffer Order { uint order[]; };
layout(std430, set = 0, binding = 5) buffer Paths { WalkState paths[]; };
layout(std430, set = 0, binding = 6) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 7) readonly buffer TriMaterial { uint triangle_material[]; };
layout(std430, set = 0, binding = 8) readonly buffer Materials { PtMaterial materials[]; };
layout(std430, set = 0, binding = 9) readonly buffer Normals { vec4 normals[]; };
layout(std430, set = 0, binding = 10) readonly buffer TriLightPmf { float tri_light_pmf[]; };
layout(std430, set = 0, binding = 11) writeonly buffer Vertices { LvcVertex vertices[]; };
layout(std430, set = 0, binding = 12) writeonly buffer Emitted { Contribution emitted[]; };

#define LVC_SHADING_NORMALS
#include "lvc_surface.glsl"

#define LVC_WALK_ARRIVE
#include "lvc_walk.glsl"

void main() {
    uint jj = linear_invocation_id();
    if (jj >= P.active_count) return;
    uint i = (C.flags & LVC_FLAG_SORTED) != 0u ? order[jj] : jj;
    uint c = live_ids[i];
    emitted[i] = Contribution(vec3(0.0), CONTRIBUTION_NONE, 0.0, CONTRIBUTION_NONE, 0u, 0u);
    Hit hit = hits[i];
    LvcVertex v;
    v.flags = 0u;
    WalkState s = paths[c];
    if (hit.triangle == MISS || !walk_arrive(s, rays[i], hit, c, v)) {
        vertices[i] = v;
        return;
    }
    uint j = v.depth;
    // A camera subpath holds at most max_depth + 1 vertices, the pinhole's included.
    if (C.max_depth < 0 || j < uint(C.max_depth)) v.flags |= VERTEX_EXTENDS;
    vertices[i] = v;
    paths[c] = s;

    vec3 le = materials[v.material].emission.rgb;
    vec3 ng = triangle_normal(v.triangle);
    float cos_l = dot(ng, v.wo);
    if (!(C.count_emitter_hit > 0.0) || le == vec3(0.0) || cos_l <= 0.0) return;
    float area = triangle_area(v.triangle);
    float pdf_area = area > 0.0 ? tri_light_pmf[v.triangle] / area : 0.0;
    float emit_dir = cos_l * LVC_INV_PI;
    // The d_vcm term's technique has one light vertex: (1, 1) when the camera sees the
    // emitter directly, else next-event estimation; both choose the point with pdf_area.
    float others = pdf_area * count_camera_vertex(C, j, true) * v.d_vcm
                 + pdf_area * emit_dir * v.d_vc;
    float weight = mis_balance(others / C.count_emitter_hit);
    emitted[i] = Contribution(v.beta * le * weight, technique_code(0u, j + 1u), weight,
                              CONTRIBUTION_NONE, 0u, 0u);
}
