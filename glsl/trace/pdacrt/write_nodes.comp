#version 460
// Next-level nodes and terminal segments, Algorithm 1 lines 13–14: each surviving child
// becomes a node of the next level (pivots re-indexed by the prefix sums, so terminal
// and dropped children leave no gaps) or a segment of the terminal-node buffer.
#include "grid.glsl"
#include "pdacrt.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Children { Child children[]; };
layout(std430, set = 0, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, set = 0, binding = 2) writeonly buffer NextNodes { Node next_nodes[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Segments { Segment segments[]; };
layout(push_constant) uniform Push {
    uint child_count;
    uint stride;
    uint segment_base;
    uint term_tri_base;
    uint term_ray_base;
} pc;

void main() {
    uint c = linear_invocation_id();
    if (c >= pc.child_count) return;
    Child ch = children[c];
    if (ch.kind == CHILD_NEXT) {
        next_nodes[offsets[CH_NEXT_FLAG * pc.stride + c]] = Node(ch.box_min, ch.box_max,
            offsets[CH_NEXT_TRIS * pc.stride + c], ch.tri_count,
            offsets[CH_NEXT_RAYS * pc.stride + c], ch.ray_count);
    } else if (ch.kind == CHILD_TERMINAL) {
        segments[pc.segment_base + offsets[CH_TERM_FLAG * pc.stride + c]] = Segment(
            pc.term_tri_base + offsets[CH_TERM_TRIS * pc.stride + c], ch.tri_count,
            pc.term_ray_base + offsets[CH_TERM_RAYS * pc.stride + c], ch.ray_count);
    }
}
