#version 460
// A level's plan in one dispatch of one workgroup (LevelSplit::PrefixSums, where both
// of the level's scans fit one workgroup: PdacrtParams::one_dispatch_plan). It does in
// order what four dispatches otherwise do: the exclusive scan of the tiles' side counts
// (`ranks`, in place), the children (children.glsl: Algorithm 2 lines 13–15 and
// Algorithm 1 line 6), the scan of their channels into `offsets` (line 11) and the
// level's totals (level_totals.glsl). On lavapipe every pipeline barrier between
// dispatches costs about 40 µs and every small dispatch 20–60 µs, about 0.2 ms per
// level in all; workgroup barriers inside one small dispatch cost far less.
//
// The arrays one invocation writes and others then read (ranks, channels, offsets) are
// coherent, with memoryBarrierBuffer before each workgroup barrier.
#include "grid.glsl"
#include "pdacrt.glsl"
#include "workgroup_scan.glsl"
#define RANKED 1

layout(buffer_reference, std430, buffer_reference_align = 4) coherent buffer CoherentUintsRef { uint data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer ChildrenWriteRef { Child data[]; };

layout(push_constant) uniform Push {
    ChildrenPush pc;
    uint ranks_len;  // words in all four side-count arrays (filter_*.comp)
    BUFFER_REF(NodesInRef, nodes)
    BUFFER_REF(CoherentUintsRef, ranks)
    BUFFER_REF(ChildrenWriteRef, children)
    BUFFER_REF(CoherentUintsRef, channels)
    BUFFER_REF(UintsInRef, bounds)
    BUFFER_REF(CoherentUintsRef, offsets)
    BUFFER_REF(UintsOutRef, totals)  // CHANNELS words
};
BUFFER_BINDING(0, readonly, Node, nodes)
BUFFER_BINDING(1, coherent, uint, ranks)
BUFFER_BINDING(2, writeonly, Child, children)
BUFFER_BINDING(3, coherent, uint, channels)
BUFFER_BINDING(4, readonly, uint, bounds)
BUFFER_BINDING(5, coherent, uint, offsets)
BUFFER_BINDING(6, writeonly, uint, totals)

#include "children.glsl"
#include "level_totals.glsl"

void main() {
    WORKGROUP_SCAN(ranks.data, ranks.data, ranks_len, false, false)
    memoryBarrierBuffer();
    barrier();
    for (uint c = gl_LocalInvocationID.x; c < pc.child_count; c += WORKGROUP_SIZE) write_child(c);
    memoryBarrierBuffer();
    barrier();
    WORKGROUP_SCAN(channels.data, offsets.data, CHANNELS * pc.stride, false, false)
    memoryBarrierBuffer();
    barrier();
    if (gl_LocalInvocationID.x == 0u) write_level_totals(pc.child_count, pc.stride);
}
