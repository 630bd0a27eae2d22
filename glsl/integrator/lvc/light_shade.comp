#version 460
// Light pass (Algorithm 7, lines 6-8), one invocation per live light path (through the
// material-sorted order when sorting is on): the vertex its ray reached, with its MIS
// quantities; a connectible vertex is marked for the light vertex cache (its ordinal
// among its path's cached vertices is the path's count so far); then the BSDF samples
// the next direction and Russian roulette decides whether the path goes on.
//
// Every output is indexed by the path's position i in the (unsorted) active list or by
// its light path l, and every random number is a function of (light path, pass,
// dimension, seed): sorting and scheduling change nothing.
#include "grid.glsl"
#include "geometry.glsl"
#include "random.glsl"
#include "bsdf.glsl"
#include "../pt/pt.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push {
    LvcPush P;
    BUFFER_REF(LvcConstantsInRef, constants)
    BUFFER_REF(RaysRef, rays)
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(UintsInRef, live_ids)
    BUFFER_REF(UintsInRef, order)
    BUFFER_REF(WalkStatesRef, paths)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(UintsInRef, triangle_material)
    BUFFER_REF(PtMaterialsInRef, materials)
    BUFFER_REF(BsdfsInRef, bsdfs)
    BUFFER_REF(Vec4sInRef, normals)
    BUFFER_REF(LvcVerticesOutRef, vertex_out)
    BUFFER_REF(UintsOutRef, stored)
    BUFFER_REF(UintsOutRef, alive)
    BUFFER_REF(UintsRef, vertex_count)
};
BUFFER_BINDING(0, readonly, LvcConstants, constants)
BUFFER_BINDING(1, , Ray, rays)
BUFFER_BINDING(2, readonly, Hit, hits)
BUFFER_BINDING(3, readonly, uint, live_ids)
BUFFER_BINDING(4, readonly, uint, order)
BUFFER_BINDING(5, , WalkState, paths)
BUFFER_BINDING(6, readonly, Triangle, triangles)
BUFFER_BINDING(7, readonly, uint, triangle_material)
BUFFER_BINDING(8, readonly, PtMaterial, materials)
BUFFER_BINDING(9, readonly, BsdfParams, bsdfs)
BUFFER_BINDING(10, readonly, vec4, normals)
BUFFER_BINDING(11, writeonly, LvcVertex, vertex_out)
BUFFER_BINDING(12, writeonly, uint, stored)
BUFFER_BINDING(13, writeonly, uint, alive)
BUFFER_BINDING(14, , uint, vertex_count)
#define C constants.data[0]

#define LVC_SHADING_NORMALS
#include "lvc_surface.glsl"
#define LVC_WALK_ARRIVE
#define LVC_WALK_SCATTER
#include "lvc_walk.glsl"

void main() {
    uint j = linear_invocation_id();
    if (j >= P.active_count) return;
    uint i = (C.flags & LVC_FLAG_SORTED) != 0u ? order.data[j] : j;
    uint l = live_ids.data[i];
    stored.data[i] = 0u;
    alive.data[i] = 0u;
    Hit hit = hits.data[i];
    if (hit.triangle == MISS) return;
    WalkState s = paths.data[l];
    LvcVertex v;
    if (!walk_arrive(s, rays.data[i], hit, l, v)) return;
    if ((v.flags & VERTEX_CONNECTIBLE) != 0u) {
        v.ordinal = vertex_count.data[l];
        vertex_count.data[l] = v.ordinal + 1u;
        stored.data[i] = 1u;
    }
    vertex_out.data[i] = v;
    // A light subpath holds at most max_depth vertices, the light's included.
    bool extends = C.max_depth < 0 || v.depth + 1u < uint(C.max_depth);
    Ray next;
    uint index = l % C.light_paths;
    uint pass = P.first_pass + l / C.light_paths;
    if (extends && walk_scatter(s, v, triangle_normal(hit.triangle), index, pass,
                                TRANSPORT_IMPORTANCE, next)) {
        rays.data[i] = next;
        alive.data[i] = 1u;
    }
    paths.data[l] = s;
}
