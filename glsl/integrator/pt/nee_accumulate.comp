#version 460
// Stage `accumulate`: a next-event contribution counts when its shadow ray reached
// the light unoccluded.
#include "grid.glsl"
#include "geometry.glsl"
#include "pt.glsl"

layout(push_constant) uniform Push { PtParams params; };
layout(std430, set = 0, binding = 0) readonly buffer Active { uint live_ids[]; };
layout(std430, set = 0, binding = 1) readonly buffer ShadowHits { Hit shadow_hits[]; };
layout(std430, set = 0, binding = 2) readonly buffer Nee { vec4 nee[]; };
layout(std430, set = 0, binding = 3) buffer Paths { PathState paths[]; };

void main() {
    uint i = linear_invocation_id();
    if (i >= params.active_count) return;
    vec4 c = nee[i];
    if (c.a == 0.0 || shadow_hits[i].triangle != MISS) return;
    uint p = live_ids[i];
    paths[p].radiance.rgb += c.rgb;
}
