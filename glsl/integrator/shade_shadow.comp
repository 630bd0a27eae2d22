#version 460
// Shading of the `shadow` integrator: emission, plus the light's contribution where the
// shadow ray found no blocker.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"
#include "film_sum.glsl"

layout(push_constant) uniform Push {
    FrameParams frame;
    BUFFER_REF(Vec4sInRef, contribution)
    BUFFER_REF(HitsInRef, shadow_hits)
    BUFFER_REF(Vec4sRef, accum)
};
BUFFER_BINDING(0, readonly, vec4, contribution)
BUFFER_BINDING(1, readonly, Hit, shadow_hits)
BUFFER_BINDING(2, , vec4, accum)

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    vec3 color = contribution.data[2u * i].rgb;
    if (shadow_hits.data[i].triangle == MISS) color += contribution.data[2u * i + 1u].rgb;
    FILM_ADD(accum.data, frame.pixel_offset + i, frame.width * frame.height, vec4(color, 1.0));
}
