#version 460
// Per-path slots of the cache (count per path -> prefix sum -> write): cache vertex k,
// the ordinal-th of light path l, gets slot path_offset[l] + ordinal of the index, so
// that the index lists each light path's vertices contiguously, in path order: pass q's
// vertices are slots path_offset[q N_L] .. path_offset[(q + 1) N_L].
#include "grid.glsl"
#include "geometry.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push { LvcPush P; };
layout(std430, set = 0, binding = 0) readonly buffer Cache { LvcVertex cache[]; };
layout(std430, set = 0, binding = 1) readonly buffer PathOffset { uint path_offset[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Index { uint cache_index[]; };

void main() {
    uint k = linear_invocation_id();
    if (k >= P.active_count) return;
    LvcVertex v = cache[k];
    cache_index[path_offset[v.path] + v.ordinal] = k;
}
