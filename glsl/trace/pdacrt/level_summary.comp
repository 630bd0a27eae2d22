#version 460
// The level's totals (level_totals.glsl) by one invocation, after the channels' scan.
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

#include "level_totals.glsl"

void main() {
    write_level_totals(pc.child_count, pc.stride);
}
