#version 460
// Stage `accumulate`: a next-event contribution counts when its shadow ray reached
// the light unoccluded.
#include "grid.glsl"
#include "geometry.glsl"
#include "pt.glsl"

layout(push_constant) uniform Push {
    PtParams params;
    BUFFER_REF(UintsInRef, live_ids)
    BUFFER_REF(HitsInRef, shadow_hits)
    BUFFER_REF(Vec4sInRef, nee)
    BUFFER_REF(PathStatesRef, paths)
};
BUFFER_BINDING(0, readonly, uint, live_ids)
BUFFER_BINDING(1, readonly, Hit, shadow_hits)
BUFFER_BINDING(2, readonly, vec4, nee)
BUFFER_BINDING(3, , PathState, paths)

void main() {
    uint i = linear_invocation_id();
    if (i >= params.active_count) return;
    vec4 c = nee.data[i];
    if (c.a == 0.0 || shadow_hits.data[i].triangle != MISS) return;
    uint p = live_ids.data[i];
    paths.data[p].radiance.rgb += c.rgb;
}
