#version 460
// Shading of the `shadow` integrator: emission, plus the light's contribution where the
// shadow ray found no blocker.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"

layout(push_constant) uniform Push { FrameParams frame; };
layout(std430, set = 0, binding = 0) readonly buffer Contribution { vec4 contribution[]; };
layout(std430, set = 0, binding = 1) readonly buffer ShadowHits { Hit shadow_hits[]; };
layout(std430, set = 0, binding = 2) buffer Accum { vec4 accum[]; };

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    vec3 color = contribution[2u * i].rgb;
    if (shadow_hits[i].triangle == MISS) color += contribution[2u * i + 1u].rgb;
    accum[frame.pixel_offset + i] += vec4(color, 1.0);
}
