#version 460
// Camera pass, after the shadow rays (Algorithm 8, line 9): each live path's radiance
// gets, in a fixed order, its emitter hit (s = 0), its direct lighting (s = 1) if the
// shadow ray reached the light, and each of its N connections whose shadow ray reached
// the cache vertex. Non-finite contributions are dropped and counted.
#include "grid.glsl"
#include "geometry.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push { LvcPush P; };
layout(std430, set = 0, binding = 0) readonly buffer Constants { LvcConstants C; };
layout(std430, set = 0, binding = 1) readonly buffer Active { uint live_ids[]; };
layout(std430, set = 0, binding = 2) readonly buffer Emitted { Contribution emitted[]; };
layout(std430, set = 0, binding = 3) readonly buffer ShadowHits { Hit shadow_hits[]; };
layout(std430, set = 0, binding = 4) readonly buffer Contributions { Contribution contrib[]; };
layout(std430, set = 0, binding = 5) buffer Radiance { vec4 radiance[]; };
layout(std430, set = 0, binding = 6) buffer Counters { uint counters[]; };

const uint COUNTER_NON_FINITE = 0u;

void add(inout vec3 sum, Contribution c) {
    if (c.code == CONTRIBUTION_NONE) return;
    if (any(isnan(c.value)) || any(isinf(c.value))) {
        atomicAdd(counters[COUNTER_NON_FINITE], 1u);
        return;
    }
    sum += c.value;
}

void main() {
    uint i = linear_invocation_id();
    uint n = P.active_count;
    if (i >= n) return;
    uint c = live_ids[i];
    vec3 sum = radiance[c].rgb;
    add(sum, emitted[i]);
    if (shadow_hits[i].triangle == MISS) add(sum, contrib[i]);
    for (uint k = 0u; k < C.connections; ++k) {
        uint slot = P.base + i * C.connections + k;
        if (shadow_hits[slot].triangle == MISS) add(sum, contrib[slot]);
    }
    radiance[c].rgb = sum;
}
