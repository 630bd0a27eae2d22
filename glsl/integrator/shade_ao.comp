#version 460
// Ambient occlusion: the fraction of a hit's AO rays that escape within ao_radius, as a
// grey level (0 for pixels whose primary ray missed). Accumulates into the film sum.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"
#include "film_sum.glsl"

layout(push_constant) uniform Push {
    FrameParams frame;
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(HitsInRef, ao_hits)
    BUFFER_REF(Vec4sRef, accum)
};
BUFFER_BINDING(0, readonly, Hit, hits)
BUFFER_BINDING(1, readonly, Hit, ao_hits)
BUFFER_BINDING(2, , vec4, accum)

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    uint pixel = frame.pixel_offset + i;
    float visible = 0.0;
    if (hits.data[i].triangle != MISS) {
        uint open = 0u;
        for (uint k = 0; k < frame.ao_rays; ++k) {
            if (ao_hits.data[i * frame.ao_rays + k].triangle == MISS) open += 1u;
        }
        visible = float(open) / float(max(frame.ao_rays, 1u));
    }
    FILM_ADD(accum.data, pixel, frame.width * frame.height, vec4(vec3(visible), 1.0));
}
