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
//
// With `tight` set (PdacrtParams::tight_boxes) it also bounds each child's triangles:
// every triangle's box, clipped to its child's half of the node box (padded by eps),
// lowers the child's (min, -max) in `bounds` by atomicMin on order-preserving bits, so
// the result does not depend on the order of the triangles. children.comp makes the
// union the child's box.
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
    uint tight;  // 1: accumulate the children's triangle bounds into `bounds`
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
    BUFFER_REF(UintsRef, bounds)
};
BUFFER_BINDING(0, readonly, Triangle, triangles)
BUFFER_BINDING(1, readonly, Node, nodes)
#ifdef RANKED
BUFFER_BINDING(2, , uint, ids)
BUFFER_BINDING(3, readonly, uvec4, tiles)
BUFFER_BINDING(4, writeonly, uint, ranks)
BUFFER_BINDING(5, , uint, bounds)
#else
BUFFER_BINDING(2, readonly, uint, ids)
BUFFER_BINDING(3, , uint, keys)
BUFFER_BINDING(4, , uint, bounds)
#endif

// A triangle's box.
void triangle_box(uint id, out vec3 lo, out vec3 hi) {
    Triangle t = triangles.data[id];
    lo = min(t.v0.xyz, min(t.v1.xyz, t.v2.xyz));
    hi = max(t.v0.xyz, max(t.v1.xyz, t.v2.xyz));
}

// The status code of a triangle with box [lo, hi] against the split of the node's box
// (lines 4–5).
uint triangle_code(vec3 lo, vec3 hi, uint axis, float mid) {
    bool left = component(lo, axis) - pc.eps <= mid;
    bool right = component(hi, axis) + pc.eps >= mid;
    return (left && right) ? CODE_BOTH : (left ? CODE_LEFT : CODE_RIGHT);
}

// Child bounds (tight boxes): per child, (min.xyz, ~max.xyz) as order-preserving bits in
// the 8 words at 8 * child, all ones before the level. A child's triangle boxes are
// clipped to its half of the node box, padded by eps: a triangle that reaches into the
// half only within eps still yields a box that is not inverted.
struct SideBounds {
    vec3 lo[2];
    vec3 hi[2];
};

SideBounds empty_bounds() {
    vec3 inf = vec3(1.0 / 0.0);
    return SideBounds(vec3[2](inf, inf), vec3[2](-inf, -inf));
}

void add_to_bounds(inout SideBounds sb, uint code, vec3 lo, vec3 hi, Node nd, uint axis, float mid) {
    bvec3 on_axis = axis_mask(axis);
    vec3 node_lo = nd.box_min - pc.eps;
    vec3 node_hi = nd.box_max + pc.eps;
    if (code != CODE_RIGHT) {  // left child: [node_lo, mid] on the axis
        vec3 half_hi = mix(node_hi, vec3(mid + pc.eps), on_axis);
        sb.lo[0] = min(sb.lo[0], max(lo, node_lo));
        sb.hi[0] = max(sb.hi[0], min(hi, half_hi));
    }
    if (code != CODE_LEFT) {  // right child: [mid, node_hi] on the axis
        vec3 half_lo = mix(node_lo, vec3(mid - pc.eps), on_axis);
        sb.lo[1] = min(sb.lo[1], max(lo, half_lo));
        sb.hi[1] = max(sb.hi[1], min(hi, node_hi));
    }
}

void lower_child_bounds(uint child, vec3 lo, vec3 hi) {
    if (lo.x > hi.x) return;  // no triangle on this side
    uint w = 8u * child;
    atomicMin(bounds.data[w + 0u], ordered_bits(lo.x));
    atomicMin(bounds.data[w + 1u], ordered_bits(lo.y));
    atomicMin(bounds.data[w + 2u], ordered_bits(lo.z));
    atomicMin(bounds.data[w + 4u], ~ordered_bits(hi.x));
    atomicMin(bounds.data[w + 5u], ~ordered_bits(hi.y));
    atomicMin(bounds.data[w + 6u], ~ordered_bits(hi.z));
}

#ifdef RANKED
// The lanes' bounds, combined by the first invocation after tile_sum's barrier.
shared SideBounds lane_bounds[WORKGROUP_SIZE];
#endif

void main() {
#ifdef RANKED
    uint tile_index = linear_group_id();
    uvec4 tile = tiles.data[tile_index];
    uint lid = gl_LocalInvocationID.x;
    Node nd = nodes.data[tile.x];
    uint axis = split_axis(nd.box_min, nd.box_max);
    float mid = split_position(nd.box_min, nd.box_max, axis);
    uvec2 counts = uvec2(0u);
    SideBounds sb = empty_bounds();
    for (uint k = lid; k < tile.z; k += WORKGROUP_SIZE) {
        uint i = tile.y + k;
        uint id = ids.data[i] & ID_MASK;
        vec3 lo, hi;
        triangle_box(id, lo, hi);
        uint code = triangle_code(lo, hi, axis, mid);
        ids.data[i] = id | (code << ID_BITS);
        counts += side_flags(code);
        if (pc.tight != 0u) add_to_bounds(sb, code, lo, hi, nd, axis, mid);
    }
    if (pc.tight != 0u) lane_bounds[lid] = sb;  // read after tile_sum's barrier
    counts = tile_sum(counts);
    if (lid == 0u) {
        ranks.data[pc.left_base + tile_index] = counts.x;
        ranks.data[pc.right_base + tile_index] = counts.y;
        if (tile_index == 0u) {
            ranks.data[pc.left_base + pc.n] = 0u;
            ranks.data[pc.right_base + pc.n] = 0u;
        }
        if (pc.tight != 0u) {
            for (uint l = 1u; l < WORKGROUP_SIZE; ++l) {
                SideBounds other = lane_bounds[l];
                for (uint s = 0u; s < 2u; ++s) {
                    sb.lo[s] = min(sb.lo[s], other.lo[s]);
                    sb.hi[s] = max(sb.hi[s], other.hi[s]);
                }
            }
            lower_child_bounds(2u * tile.x, sb.lo[0], sb.hi[0]);
            lower_child_bounds(2u * tile.x + 1u, sb.lo[1], sb.hi[1]);
        }
    }
#else
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    uint node = keys.data[i] >> 2;
    Node nd = nodes.data[node];
    uint axis = split_axis(nd.box_min, nd.box_max);
    float mid = split_position(nd.box_min, nd.box_max, axis);
    vec3 lo, hi;
    triangle_box(ids.data[i], lo, hi);
    uint code = triangle_code(lo, hi, axis, mid);
    keys.data[i] = (node << 2) | code;
    if (pc.tight != 0u) {
        SideBounds sb = empty_bounds();
        add_to_bounds(sb, code, lo, hi, nd, axis, mid);
        lower_child_bounds(2u * node, sb.lo[0], sb.hi[0]);
        lower_child_bounds(2u * node + 1u, sb.lo[1], sb.hi[1]);
    }
#endif
}
