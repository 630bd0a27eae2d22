#version 460
// Camera pass, stream 2 (Algorithm 8, line 8): the next bounce — BSDF sampling, Russian
// roulette and the pending MIS update (src/bidir/walk.rs `Walk::scatter`) — and the
// next ray of every camera path that goes on.
#include "grid.glsl"
#include "geometry.glsl"
#include "random.glsl"
#include "bsdf.glsl"
#include "../pt/pt.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push { LvcPush P; };
layout(std430, set = 0, binding = 0) readonly buffer Constants { LvcConstants C; };
layout(std430, set = 0, binding = 1) writeonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 2) readonly buffer Active { uint live_ids[]; };
layout(std430, set = 0, binding = 3) readonly buffer Order { uint order[]; };
layout(std430, set = 0, binding = 4) readonly buffer Vertices { LvcVertex vertices[]; };
layout(std430, set = 0, binding = 5) buffer Paths { WalkState paths[]; };
layout(std430, set = 0, binding = 6) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 7) readonly buffer Bsdfs { BsdfParams bsdfs[]; };
layout(std430, set = 0, binding = 8) writeonly buffer Alive { uint alive[]; };

#include "lvc_surface.glsl"
#define LVC_WALK_SCATTER
#include "lvc_walk.glsl"

void main() {
    uint jj = linear_invocation_id();
    if (jj >= P.active_count) return;
    uint i = (C.flags & LVC_FLAG_SORTED) != 0u ? order[jj] : jj;
    alive[i] = 0u;
    LvcVertex v = vertices[i];
    uint need = VERTEX_VALID | VERTEX_EXTENDS;
    if ((v.flags & need) != need) return;
    uint c = live_ids[i];
    uint pixel = P.pixel_offset + c % P.pixel_count;
    uint pass = P.first_pass + c / P.pixel_count;
    WalkState s = paths[c];
    Ray next;
    if (walk_scatter(s, v, triangle_normal(v.triangle), pixel, pass, TRANSPORT_RADIANCE, next)) {
        rays[i] = next;
        alive[i] = 1u;
    }
    paths[c] = s;
}
