#version 460
// The eight totals of a level (next-level nodes, triangle ids, ray ids; terminal nodes,
// triangle ids, ray ids; next-level triangle and ray tiles): exclusive sum at the last child plus its own value. The host
// reads these 32 bytes once per level to size the next level (Algorithm 1 line 11) and
// to decide whether the terminal-node buffer must be flushed first (line 7).
#include "pdacrt.glsl"
layout(local_size_x = 1) in;
layout(std430, set = 0, binding = 0) readonly buffer Channels { uint channels[]; };
layout(std430, set = 0, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Summary { uint totals[CHANNELS]; };
layout(push_constant) uniform Push { uint child_count; uint stride; } pc;
void main() {
    uint last = pc.child_count - 1u;
    for (uint k = 0u; k < CHANNELS; ++k) {
        totals[k] = CHANNEL_OFFSET(offsets, pc.stride, k, last) + channels[k * pc.stride + last];
    }
}
