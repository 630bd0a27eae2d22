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

struct FilterTrianglesPush {
    uint n;  // list length (ranked: the tile count, also the dispatch size)
    float eps;
    uint left_base;
    uint right_base;
};
layout(push_constant) uniform Push {
    FilterTrianglesPush pc;
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(NodesInRef, nodes)
#ifdef RANKED
    BUFFER_REF(UintsRef, ids)
    BUFFER_REF(Uvec4sInRef, tiles)
    BUFFER_REF(UintsOutRef, ranks)
#else
    BUFFER_REF(UintsInRef, ids)
    BUFFER_REF(UintsRef, keys)
#endif

};
BUFFER_BINDING(0, readonly, Triangle, triangles)
BUFFER_BINDING(1, readonly, Node, nodes)
#ifdef RANKED
BUFFER_BINDING(2, , uint, ids)
BUFFER_BINDING(3, readonly, uvec4, tiles)
BUFFER_BINDING(4, writeonly, uint, ranks)
#else
BUFFER_BINDING(2, readonly, uint, ids)
BUFFER_BINDING(3, , uint, keys)
#endif

// The status code of triangle `id` against the split of the node's box (lines 4–5).
uint triangle_code(uint id, uint axis, float mid) {
    Triangle t = triangles.data[id];
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
    uvec4 tile = tiles.data[tile_index];
    uint lid = gl_LocalInvocationID.x;
    Node nd = nodes.data[tile.x];
    uint axis = split_axis(nd.box_min, nd.box_max);
    float mid = split_position(nd.box_min, nd.box_max, axis);
    uvec2 counts = uvec2(0u);
    for (uint k = lid; k < tile.z; k += WORKGROUP_SIZE) {
        uint i = tile.y + k;
        uint id = ids.data[i] & ID_MASK;
        uint code = triangle_code(id, axis, mid);
        ids.data[i] = id | (code << ID_BITS);
        counts += side_flags(code);
    }
    counts = tile_sum(counts);
    if (lid == 0u) {
        ranks.data[pc.left_base + tile_index] = counts.x;
        ranks.data[pc.right_base + tile_index] = counts.y;
        if (tile_index == 0u) {
            ranks.data[pc.left_base + pc.n] = 0u;
            ranks.data[pc.right_base + pc.n] = 0u;
        }
    }
#else
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    uint node = keys.data[i] >> 2;
    Node nd = nodes.data[node];
    uint axis = split_axis(nd.box_min, nd.box_max);
    float mid = split_position(nd.box_min, nd.box_max, axis);
    keys.data[i] = (node << 2) | triangle_code(ids.data[i], axis, mid);
#endif
}
