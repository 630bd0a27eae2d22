#version 460
// Ambient occlusion: the fraction of a hit's AO rays that escape within ao_radius, as a
// grey level (0 for pixels whose primary ray missed). Accumulates into the film sum.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"

layout(push_constant) uniform Push { FrameParams frame; };
layout(std430, set = 0, binding = 0) readonly buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 1) readonly buffer AoHits { Hit ao_hits[]; };
layout(std430, set = 0, binding = 2) buffer Accum { vec4 accum[]; };

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    uint pixel = frame.pixel_offset + i;
    float visible = 0.0;
    if (hits[i].triangle != MISS) {
        uint open = 0u;
        for (uint k = 0; k < frame.ao_rays; ++k) {
            if (ao_hits[i * frame.ao_rays + k].triangle == MISS) open += 1u;
        }
        visible = float(open) / float(max(frame.ao_rays, 1u));
    }
    accum[pixel] += vec4(vec3(visible), 1.0);
}
