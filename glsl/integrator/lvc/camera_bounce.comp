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

layout(push_constant) uniform Push {
    LvcPush P;
    BUFFER_REF(LvcConstantsInRef, constants)
    BUFFER_REF(RaysOutRef, rays)
    BUFFER_REF(UintsInRef, live_ids)
    BUFFER_REF(UintsInRef, order)
    BUFFER_REF(LvcVerticesInRef, vertices)
    BUFFER_REF(WalkStatesRef, paths)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(BsdfsInRef, bsdfs)
    BUFFER_REF(UintsOutRef, alive)
};
BUFFER_BINDING(0, readonly, LvcConstants, constants)
BUFFER_BINDING(1, writeonly, Ray, rays)
BUFFER_BINDING(2, readonly, uint, live_ids)
BUFFER_BINDING(3, readonly, uint, order)
BUFFER_BINDING(4, readonly, LvcVertex, vertices)
BUFFER_BINDING(5, , WalkState, paths)
BUFFER_BINDING(6, readonly, Triangle, triangles)
BUFFER_BINDING(7, readonly, BsdfParams, bsdfs)
BUFFER_BINDING(8, writeonly, uint, alive)
#define C constants.data[0]

#include "lvc_surface.glsl"
#define LVC_WALK_SCATTER
#include "lvc_walk.glsl"

void main() {
    uint jj = linear_invocation_id();
    if (jj >= P.active_count) return;
    uint i = (C.flags & LVC_FLAG_SORTED) != 0u ? order.data[jj] : jj;
    alive.data[i] = 0u;
    LvcVertex v = vertices.data[i];
    uint need = VERTEX_VALID | VERTEX_EXTENDS;
    if ((v.flags & need) != need) return;
    uint c = live_ids.data[i];
    uint pixel = P.pixel_offset + c % P.pixel_count;
    uint pass = P.first_pass + c / P.pixel_count;
    WalkState s = paths.data[c];
    Ray next;
    if (walk_scatter(s, v, triangle_normal(v.triangle), pixel, pass, TRANSPORT_RADIANCE, next)) {
        rays.data[i] = next;
        alive.data[i] = 1u;
    }
    paths.data[c] = s;
}
