#version 460
// Copies n u32 words: the smallest kernel, used by runtime tests (round trips, streams).
layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer Src { uint src[]; };
layout(std430, binding = 1) writeonly buffer Dst { uint dst[]; };
layout(push_constant) uniform Push { uint n; uint add; } pc;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < pc.n) dst[i] = src[i] + pc.add;
}
