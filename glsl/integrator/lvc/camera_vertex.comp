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

layout(push_constant) uniform Push {
    LvcPush P;
    BUFFER_REF(LvcConstantsInRef, constants)
    BUFFER_REF(RaysInRef, rays)
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(UintsInRef, live_ids)
    BUFFER_REF(UintsInRef, order)
    BUFFER_REF(WalkStatesRef, paths)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(UintsInRef, triangle_material)
    BUFFER_REF(PtMaterialsInRef, materials)
    BUFFER_REF(Vec4sInRef, normals)
    BUFFER_REF(FloatsInRef, tri_light_pmf)
    BUFFER_REF(LvcVerticesOutRef, vertices)
    BUFFER_REF(ContributionsOutRef, emitted)
};
BUFFER_BINDING(0, readonly, LvcConstants, constants)
BUFFER_BINDING(1, readonly, Ray, rays)
BUFFER_BINDING(2, readonly, Hit, hits)
BUFFER_BINDING(3, readonly, uint, live_ids)
BUFFER_BINDING(4, readonly, uint, order)
BUFFER_BINDING(5, , WalkState, paths)
BUFFER_BINDING(6, readonly, Triangle, triangles)
BUFFER_BINDING(7, readonly, uint, triangle_material)
BUFFER_BINDING(8, readonly, PtMaterial, materials)
BUFFER_BINDING(9, readonly, vec4, normals)
BUFFER_BINDING(10, readonly, float, tri_light_pmf)
BUFFER_BINDING(11, writeonly, LvcVertex, vertices)
BUFFER_BINDING(12, writeonly, Contribution, emitted)
#define C constants.data[0]

#define LVC_SHADING_NORMALS
#include "lvc_surface.glsl"

#define LVC_WALK_ARRIVE
#include "lvc_walk.glsl"

void main() {
    uint jj = linear_invocation_id();
    if (jj >= P.active_count) return;
    uint i = (C.flags & LVC_FLAG_SORTED) != 0u ? order.data[jj] : jj;
    uint c = live_ids.data[i];
    emitted.data[i] = Contribution(vec3(0.0), CONTRIBUTION_NONE, 0.0, CONTRIBUTION_NONE, 0u, 0u);
    Hit hit = hits.data[i];
    LvcVertex v;
    v.flags = 0u;
    WalkState s = paths.data[c];
    if (hit.triangle == MISS || !walk_arrive(s, rays.data[i], hit, c, v)) {
        vertices.data[i] = v;
        return;
    }
    uint j = v.depth;
    // A camera subpath holds at most max_depth + 1 vertices, the pinhole's included.
    if (C.max_depth < 0 || j < uint(C.max_depth)) v.flags |= VERTEX_EXTENDS;
    vertices.data[i] = v;
    paths.data[c] = s;

    vec3 le = materials.data[v.material].emission.rgb;
    vec3 ng = triangle_normal(v.triangle);
    float cos_l = dot(ng, v.wo);
    if (!(C.count_emitter_hit > 0.0) || le == vec3(0.0) || cos_l <= 0.0) return;
    float area = triangle_area(v.triangle);
    float pdf_area = area > 0.0 ? tri_light_pmf.data[v.triangle] / area : 0.0;
    float emit_dir = cos_l * LVC_INV_PI;
    // The d_vcm term's technique has one light vertex: (1, 1) when the camera sees the
    // emitter directly, else next-event estimation; both choose the point with pdf_area.
    float others = pdf_area * count_camera_vertex(C, j, true) * v.d_vcm
                 + pdf_area * emit_dir * v.d_vc;
    float weight = mis_balance(others / C.count_emitter_hit);
    emitted.data[i] = Contribution(v.beta * le * weight, technique_code(0u, j + 1u), weight,
                                   CONTRIBUTION_NONE, 0u, 0u);
}
