#version 460
// Triangle filtering, Algorithm 2 lines 2–6: split the node's box (line 4), test the
// triangle against the two halves (line 5) and write its status code (line 6) into the
// low 2 bits of its key, whose high bits already hold its node.
//
// The test is bounding-box overlap along the split axis: the halves equal the parent box
// on the other axes, which the triangle already overlaps. Boxes are padded by `eps` so
// rounding can only add work, never lose a hit.
//
// The `ranked` variant (LevelSplit::PrefixSums) also writes the element's side flags —
// 1 where it belongs to the left (right) child — into `ranks` at left_base + i
// (right_base + i). One exclusive scan of all flag arrays then ranks every element
// within its child (see children.comp). Invocation n writes the zero flags that close
// each array, so the scan's value at n is the array's total.
//! variant ranked: RANKED=1
#include "grid.glsl"
#include "geometry.glsl"
#include "pdacrt.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 1) readonly buffer Nodes { Node nodes[]; };
layout(std430, set = 0, binding = 2) readonly buffer Ids { uint ids[]; };
layout(std430, set = 0, binding = 3) buffer Keys { uint keys[]; };
#ifdef RANKED
layout(std430, set = 0, binding = 4) writeonly buffer Ranks { uint ranks[]; };
#endif
layout(push_constant) uniform Push { uint n; float eps; uint left_base; uint right_base; } pc;

void main() {
    uint i = linear_invocation_id();
#ifdef RANKED
    if (i == pc.n) {
        ranks[pc.left_base + i] = 0u;
        ranks[pc.right_base + i] = 0u;
    }
#endif
    if (i >= pc.n) return;
    uint node = keys[i] >> 2;
    Node nd = nodes[node];
    uint axis = split_axis(nd.box_min.xyz, nd.box_max.xyz);
    float mid = split_position(nd.box_min.xyz, nd.box_max.xyz, axis);
    Triangle t = triangles[ids[i]];
    float a = t.v0[axis];
    float b = a + t.e1[axis];
    float c = a + t.e2[axis];
    bool left = min(a, min(b, c)) - pc.eps <= mid;
    bool right = max(a, max(b, c)) + pc.eps >= mid;
    uint code = (left && right) ? CODE_BOTH : (left ? CODE_LEFT : CODE_RIGHT);
    keys[i] = (node << 2) | code;
#ifdef RANKED
    ranks[pc.left_base + i] = uint(code != CODE_RIGHT);
    ranks[pc.right_base + i] = uint(code != CODE_LEFT);
#endif
}
