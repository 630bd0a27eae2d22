#version 460
// Light tracing's splats: each unoccluded contribution is added to its (pass, pixel)
// slot of the splat film in Q32.32 fixed point with integer atomics (lvc_fixed.glsl), so
// the film does not depend on the order of the additions, scaled by the film's power of
// two so that the scene's radiance sits in the middle of the fixed-point range.
// Non-finite values are dropped and counted.
#include "grid.glsl"
#include "geometry.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push {
    LvcPush P;
    BUFFER_REF(ContributionsInRef, contrib)
    BUFFER_REF(HitsInRef, shadow_hits)
    BUFFER_REF(UintsRef, fixed_film)
    BUFFER_REF(UintsRef, counters)
    BUFFER_REF(LvcConstantsInRef, constants)
};
BUFFER_BINDING(0, readonly, Contribution, contrib)
BUFFER_BINDING(1, readonly, Hit, shadow_hits)
BUFFER_BINDING(2, , uint, fixed_film)
BUFFER_BINDING(3, , uint, counters)
BUFFER_BINDING(4, readonly, LvcConstants, constants)
#define C constants.data[0]

#define LVC_FIXED_ADD
#include "lvc_fixed.glsl"

void main() {
    uint k = linear_invocation_id();
    if (k >= P.active_count) return;
    Contribution c = contrib.data[k];
    if (c.code == CONTRIBUTION_NONE || shadow_hits.data[k].triangle != MISS) return;
    if (any(isnan(c.value)) || any(isinf(c.value))) {
        atomicAdd(counters.data[COUNTER_NON_FINITE], 1u);
        return;
    }
    fixed_add(c.target, c.value * C.brightness_scale);
}
