#version 460
// Writes the FrameParams push constants back as 32 words, so tests/suite/render.rs can prove
// the Rust and GLSL layouts agree.
#include "frame.glsl"
layout(local_size_x = 1) in;
layout(push_constant) uniform Push { FrameParams frame; };
layout(std430, set = 0, binding = 0) writeonly buffer Out { uint words[32]; };
void main() {
    for (uint k = 0u; k < 4u; ++k) {
        words[k] = floatBitsToUint(frame.origin[k]);
        words[4u + k] = floatBitsToUint(frame.forward[k]);
        words[8u + k] = floatBitsToUint(frame.right[k]);
        words[12u + k] = floatBitsToUint(frame.up[k]);
        words[28u + k] = floatBitsToUint(frame.light[k]);
    }
    words[16] = frame.width;
    words[17] = frame.height;
    words[18] = frame.sample_index;
    words[19] = frame.seed;
    words[20] = frame.pixel_offset;
    words[21] = frame.pixel_count;
    words[22] = frame.jitter;
    words[23] = frame.ao_rays;
    words[24] = floatBitsToUint(frame.ao_radius);
    words[25] = floatBitsToUint(frame.ray_epsilon);
    words[26] = frame.bounce;
    words[27] = frame.pad0;
}
