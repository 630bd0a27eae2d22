#version 460
// The eight totals of a level (next-level nodes, triangle ids, ray ids; terminal nodes,
// triangle ids, ray ids; next-level triangle and ray tiles): exclusive sum at the last child plus its own value. The host
// reads these 32 bytes once per level to size the next level (Algorithm 1 line 11) and
// to decide whether the terminal-node buffer must be flushed first (line 7).
#include "pdacrt.glsl"
layout(local_size_x = 1) in;
struct SummaryPush {
    uint child_count;
    uint stride;
};
layout(push_constant) uniform Push {
    SummaryPush pc;
    BUFFER_REF(UintsInRef, channels)
    BUFFER_REF(UintsInRef, offsets)
    BUFFER_REF(UintsOutRef, totals)  // CHANNELS words

};
BUFFER_BINDING(0, readonly, uint, channels)
BUFFER_BINDING(1, readonly, uint, offsets)
BUFFER_BINDING(2, writeonly, uint, totals)
void main() {
    uint last = pc.child_count - 1u;
    for (uint k = 0u; k < CHANNELS; ++k) {
        totals.data[k] = CHANNEL_OFFSET(offsets.data, pc.stride, k, last)
                          + channels.data[k * pc.stride + last];
    }
}
