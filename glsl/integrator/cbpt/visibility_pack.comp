#version 460
// CBPT visibility, step 2 of 2: one bit per segment of the batch, 32 to a word (bit b
// of word w is segment 32w + b of the batch): set when the segment's ray has a positive
// reach and the tracer found no occluder. One thread per word.
#include "grid.glsl"
#include "geometry.glsl"
#include "cbpt.glsl"

layout(push_constant) uniform Push { CbptPush pc; };
layout(std430, set = 0, binding = 0) readonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 1) readonly buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Words { uint words[]; };

void main() {
    uint w = linear_invocation_id();
    uint first = w * 32u;
    if (first >= pc.count) return;
    uint word = 0u;
    uint end = min(first + 32u, pc.count);
    for (uint i = first; i < end; ++i) {
        bool free = hits[i].triangle == MISS && rays[i].tmax > 0.0;
        word |= uint(free) << (i - first);
    }
    words[w] = word;
}
