#version 460
// Light tracing's splats: each unoccluded contribution is added to its (pass, pixel)
// slot of the splat film in Q32.32 fixed point with integer atomics (lvc_fixed.glsl), so
// the film does not depend on the order of the additions, scaled by the film's power of
// two so that the scene's radiance sits in the middle of the fixed-point range.
// Non-finite values are dropped and counted.
#include "grid.glsl"
#include "geometry.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push { LvcPush P; };
layout(std430, set = 0, binding = 0) readonly buffer Contributions { Contribution contrib[]; };
layout(std430, set = 0, binding = 1) readonly buffer ShadowHits { Hit shadow_hits[]; };
layout(std430, set = 0, binding = 2) buffer FixedFilm { uint fixed_film[]; };
layout(std430, set = 0, binding = 3) buffer Counters { uint counters[]; };
layout(std430, set = 0, binding = 4) readonly buffer Constants { LvcConstants C; };

#define LVC_FIXED_ADD
#include "lvc_fixed.glsl"

void main() {
    uint k = linear_invocation_id();
    if (k >= P.active_count) return;
    Contribution c = contrib[k];
    if (c.code == CONTRIBUTION_NONE || shadow_hits[k].triangle != MISS) return;
    if (any(isnan(c.value)) || any(isinf(c.value))) {
        atomicAdd(counters[COUNTER_NON_FINITE], 1u);
        return;
    }
    fixed_add(c.target, c.value * C.brightness_scale);
}
