#version 460
// dst[i] = src[i] + add for i < n: the smallest kernel, used by the runtime tests
// (round trips, 2-D grids, streams ordered by timeline semaphores).
#include "grid.glsl"
layout(std430, set = 0, binding = 0) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Dst { uint dst[]; };
layout(push_constant) uniform Push { uint n; uint add; } pc;
void main() {
    uint i = linear_invocation_id();
    if (i < pc.n) dst[i] = src[i] + pc.add;
}
