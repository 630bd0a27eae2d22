#version 460
// Triangle filtering, Algorithm 2 lines 2–6: split the node's box (line 4), test the
// triangle against the two halves (line 5) and write its status code (line 6) into the
// low 2 bits of its key, whose high bits already hold its node.
//
// The test is bounding-box overlap along the split axis: the halves equal the parent box
// on the other axes, which the triangle already overlaps. Boxes are padded by `eps` so
// rounding can only add work, never lose a hit.
//
// The `ranked` variant (LevelSplit::PrefixSums) works per tile (pdacrt.glsl): one
// workgroup per tile, the node's split read once. It keeps the code in the id's top
// bits and writes the tile's side counts — how many of its elements belong to the left
// (right) child — into `ranks` at left_base + tile (right_base + tile). One exclusive
// scan of all count arrays then ranks every tile within its child (see children.comp;
// scatter_elements.comp ranks the elements within their tile). The first workgroup also
// writes the zero counts at n (the tile count) that close each array, so the scan's
// value at n is the array's total.
//! variant ranked: RANKED=1
#include "grid.glsl"
#include "geometry.glsl"
#include "pdacrt.glsl"
#ifdef RANKED
#include "tile_lanes.glsl"
#endif

layout(std430, set = 0, binding = 0) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 1) readonly buffer Nodes { Node nodes[]; };
#ifdef RANKED
layout(std430, set = 0, binding = 2) buffer Ids { uint ids[]; };
layout(std430, set = 0, binding = 3) readonly buffer Tiles { uvec4 tiles[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Ranks { uint ranks[]; };
#else
layout(std430, set = 0, binding = 2) readonly buffer Ids { uint ids[]; };
layout(std430, set = 0, binding = 3) buffer Keys { uint keys[]; };
#endif
// n: list length (ranked: the tile count, also the dispatch size)
layout(push_constant) uniform Push { uint n; float eps; uint left_base; uint right_base; } pc;

// The status code of triangle `id` against the split of the node's box (lines 4–5).
uint triangle_code(uint id, uint axis, float mid) {
    Triangle t = triangles[id];
    float a = component(t.v0.xyz, axis);
    float b = a + component(t.e1.xyz, axis);
    float c = a + component(t.e2.xyz, axis);
    bool left = min(a, min(b, c)) - pc.eps <= mid;
    bool right = max(a, max(b, c)) + pc.eps >= mid;
    return (left && right) ? CODE_BOTH : (left ? CODE_LEFT : CODE_RIGHT);
}

void main() {
#ifdef RANKED
    uint tile_index = linear_group_id();
    uvec4 tile = tiles[tile_index];
    uint lid = gl_LocalInvocationID.x;
    Node nd = nodes[tile.x];
    uint axis = split_axis(nd.box_min, nd.box_max);
    float mid = split_position(nd.box_min, nd.box_max, axis);
    uvec2 counts = uvec2(0u);
    for (uint k = lid; k < tile.z; k += WORKGROUP_SIZE) {
        uint i = tile.y + k;
        uint id = ids[i] & ID_MASK;
        uint code = triangle_code(id, axis, mid);
        ids[i] = id | (code << ID_BITS);
        counts += side_flags(code);
    }
    counts = tile_sum(counts);
    if (lid == 0u) {
        ranks[pc.left_base + tile_index] = counts.x;
        ranks[pc.right_base + tile_index] = counts.y;
        if (tile_index == 0u) {
            ranks[pc.left_base + pc.n] = 0u;
            ranks[pc.right_base + pc.n] = 0u;
        }
    }
#else
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    uint node = keys[i] >> 2;
    Node nd = nodes[node];
    uint axis = split_axis(nd.box_min, nd.box_max);
    float mid = split_position(nd.box_min, nd.box_max, axis);
    keys[i] = (node << 2) | triangle_code(ids[i], axis, mid);
#endif
}
