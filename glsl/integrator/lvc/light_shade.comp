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

layout(push_constant) uniform Push { LvcPush P; };
layout(std430, set = 0, binding = 0) readonly buffer Constants { LvcConstants C; };
layout(std430, set = 0, binding = 1) buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 2) readonly buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 3) readonly buffer Active { uint live_ids[]; };
layout(std430, set = 0, binding = 4) readonly buffer Order { uint order[]; };
layout(std430, set = 0, binding = 5) buffer Paths { WalkState paths[]; };
layout(std430, set = 0, binding = 6) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 7) readonly buffer TriMaterial { uint triangle_material[]; };
layout(std430, set = 0, binding = 8) readonly buffer Materials { PtMaterial materials[]; };
layout(std430, set = 0, binding = 9) readonly buffer Bsdfs { BsdfParams bsdfs[]; };
layout(std430, set = 0, binding = 10) readonly buffer Normals { vec4 normals[]; };
layout(std430, set = 0, binding = 11) writeonly buffer VertexOut { LvcVertex vertex_out[]; };
layout(std430, set = 0, binding = 12) writeonly buffer Stored { uint stored[]; };
layout(std430, set = 0, binding = 13) writeonly buffer Alive { uint alive[]; };
layout(std430, set = 0, binding = 14) buffer VertexCount { uint vertex_count[]; };

#define LVC_SHADING_NORMALS
#include "lvc_surface.glsl"
#define LVC_WALK_ARRIVE
#define LVC_WALK_SCATTER
#include "lvc_walk.glsl"

void main() {
    uint j = linear_invocation_id();
    if (j >= P.active_count) return;
    uint i = (C.flags & LVC_FLAG_SORTED) != 0u ? order[j] : j;
    uint l = live_ids[i];
    stored[i] = 0u;
    alive[i] = 0u;
    Hit hit = hits[i];
    if (hit.triangle == MISS) return;
    WalkState s = paths[l];
    LvcVertex v;
    if (!walk_arrive(s, rays[i], hit, l, v)) return;
    if ((v.flags & VERTEX_CONNECTIBLE) != 0u) {
        v.ordinal = vertex_count[l];
        vertex_count[l] = v.ordinal + 1u;
        stored[i] = 1u;
    }
    vertex_out[i] = v;
    // A light subpath holds at most max_depth vertices, the light's included.
    bool extends = C.max_depth < 0 || v.depth + 1u < uint(C.max_depth);
    Ray next;
    uint index = l % C.light_paths;
    uint pass = P.first_pass + l / C.light_paths;
    if (extends && walk_scatter(s, v, triangle_normal(hit.triangle), index, pass,
                                TRANSPORT_IMPORTANCE, next)) {
        rays[i] = next;
        alive[i] = 1u;
    }
    paths[l] = s;
}
