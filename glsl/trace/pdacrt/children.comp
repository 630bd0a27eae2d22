#version 460
// Child pivots and terminal marking, Algorithm 2 lines 13–15 and Algorithm 1 line 6.
// Node p's sorted lists hold its elements as [left | both | right | none], so its left
// child takes [start, start + L + B) and its right child [start + L, start + L + B + R).
// A child with no triangles or no rays is dropped (nothing to intersect); one with fewer
// than α triangles or β rays, at the depth limit, or too thin to split further is
// terminal; the rest form the next level. Writes the six channels that are then
// prefix-summed into next-level and terminal-buffer positions (CH_TERM_FLAG counts the
// segments a terminal child becomes; the tile channels, the next level's tiles).
//
// The `ranked` variant (LevelSplit::PrefixSums) works on the unsorted lists instead: the
// exclusive scan of the tiles' side counts (filter_*.comp) gives each child's size as
// the difference of the ranks at the node's end (the tile after its last) and start
// (its first tile), and the rank at the start serves as the child's source offset
// (scatter_elements.comp subtracts it).
//
// With `tight` set (PdacrtParams::tight_boxes) a child's box is the union of its
// triangles' boxes clipped to its half (filter_triangles.comp) instead of the half
// itself, and "too thin to split" looks at its largest extent, the axis it would split.
//! variant ranked: RANKED=1
#include "grid.glsl"
#include "pdacrt.glsl"

struct ChildrenPush {
    uint child_count;
    uint stride;
    uint alpha;
    uint beta;
    uint last_level;  // 1: every surviving child is terminal (depth limit)
    float min_extent;
    uint max_segment_rays;
    uint tile_items;
    // ranked: where each side-flag array starts in `ranks`
    uint tri_left_base;
    uint tri_right_base;
    uint ray_left_base;
    uint ray_right_base;
    uint tight;  // 1: the child's box is its triangles' bounds (`bounds`)
    uint terminal_cost;  // > 0: few rays make a child terminal only below this many tests
};
layout(push_constant) uniform Push {
    ChildrenPush pc;
    BUFFER_REF(NodesInRef, nodes)
#ifdef RANKED
    BUFFER_REF(UintsInRef, ranks)
#else
    BUFFER_REF(UintsInRef, tri_counts)
    BUFFER_REF(UintsInRef, ray_counts)
#endif
    BUFFER_REF(ChildrenOutRef, children)
    BUFFER_REF(UintsOutRef, channels)
    BUFFER_REF(UintsInRef, bounds)
};
BUFFER_BINDING(0, readonly, Node, nodes)
#ifdef RANKED
BUFFER_BINDING(1, readonly, uint, ranks)
BUFFER_BINDING(2, writeonly, Child, children)
BUFFER_BINDING(3, writeonly, uint, channels)
BUFFER_BINDING(4, readonly, uint, bounds)
#else
BUFFER_BINDING(1, readonly, uint, tri_counts)
BUFFER_BINDING(2, readonly, uint, ray_counts)
BUFFER_BINDING(3, writeonly, Child, children)
BUFFER_BINDING(4, writeonly, uint, channels)
BUFFER_BINDING(5, readonly, uint, bounds)
#endif

// Whether a child has too few rays to split (the β test, Algorithm 1 line 6). With a
// `terminal_cost` (PdacrtParams::terminal_cost) a child below β rays still splits while
// its brute force would cost that many ray-triangle tests or more: a handful of rays
// over thousands of triangles goes on down.
bool few_rays(uint rays, uint tris) {
    return rays < pc.beta && (pc.terminal_cost == 0u || float(rays) * float(tris) < float(pc.terminal_cost));
}

void main() {
    uint c = linear_invocation_id();
    if (c >= pc.child_count) return;
    uint p = c >> 1;
    bool right = (c & 1u) != 0u;
    Node nd = nodes.data[p];
    Child ch;
#ifdef RANKED
    uint tri_base = right ? pc.tri_right_base : pc.tri_left_base;
    uint ray_base = right ? pc.ray_right_base : pc.ray_left_base;
    uint tri_end = nd.first_tri_tile + (nd.tri_count + pc.tile_items - 1u) / pc.tile_items;
    uint ray_end = nd.first_ray_tile + (nd.ray_count + pc.tile_items - 1u) / pc.tile_items;
    ch.tri_src = ranks.data[tri_base + nd.first_tri_tile];
    ch.ray_src = ranks.data[ray_base + nd.first_ray_tile];
    ch.tri_count = ranks.data[tri_base + tri_end] - ch.tri_src;
    ch.ray_count = ranks.data[ray_base + ray_end] - ch.ray_src;
#else
    uint q = 4u * p;
    uvec3 tc = uvec3(tri_counts.data[q + CODE_LEFT], tri_counts.data[q + CODE_BOTH],
                     tri_counts.data[q + CODE_RIGHT]);
    uvec3 rc = uvec3(ray_counts.data[q + CODE_LEFT], ray_counts.data[q + CODE_BOTH],
                     ray_counts.data[q + CODE_RIGHT]);
    ch.tri_count = right ? tc.y + tc.z : tc.x + tc.y;
    ch.ray_count = right ? rc.y + rc.z : rc.x + rc.y;
    ch.tri_src = nd.tri_start + (right ? tc.x : 0u);
    ch.ray_src = nd.ray_start + (right ? rc.x : 0u);
#endif
    uint axis = split_axis(nd.box_min, nd.box_max);
    float mid = split_position(nd.box_min, nd.box_max, axis);
    ch.box_min = vec4(nd.box_min, 0.0);
    ch.box_max = vec4(nd.box_max, 0.0);
    if (right) ch.box_min[axis] = mid; else ch.box_max[axis] = mid;
    float extent = ch.box_max[axis] - ch.box_min[axis];
    if (pc.tight != 0u && ch.tri_count != 0u) {
        uint w = 8u * c;
        ch.box_min.xyz = child_bounds_min(uvec3(bounds.data[w], bounds.data[w + 1u], bounds.data[w + 2u]));
        ch.box_max.xyz = child_bounds_max(uvec3(bounds.data[w + 4u], bounds.data[w + 5u], bounds.data[w + 6u]));
        vec3 e = ch.box_max.xyz - ch.box_min.xyz;
        extent = max(e.x, max(e.y, e.z));
    }
    if (ch.tri_count == 0u || ch.ray_count == 0u) {
        ch.kind = CHILD_DROPPED;
    } else if (ch.tri_count < pc.alpha || few_rays(ch.ray_count, ch.tri_count) || pc.last_level != 0u
               || extent <= pc.min_extent) {
        ch.kind = CHILD_TERMINAL;
    } else {
        ch.kind = CHILD_NEXT;
    }
    ch.pad0 = 0u;
    ch.pad1 = 0u;
    ch.pad2 = 0u;
    children.data[c] = ch;
    bool next = ch.kind == CHILD_NEXT;
    bool term = ch.kind == CHILD_TERMINAL;
    channels.data[CH_NEXT_FLAG * pc.stride + c] = next ? 1u : 0u;
    channels.data[CH_NEXT_TRIS * pc.stride + c] = next ? ch.tri_count : 0u;
    channels.data[CH_NEXT_RAYS * pc.stride + c] = next ? ch.ray_count : 0u;
    // A terminal node with many rays becomes several segments (see write_nodes.comp).
    channels.data[CH_TERM_FLAG * pc.stride + c] = term ? (ch.ray_count + pc.max_segment_rays - 1u) / pc.max_segment_rays : 0u;
    channels.data[CH_TERM_TRIS * pc.stride + c] = term ? ch.tri_count : 0u;
    channels.data[CH_TERM_RAYS * pc.stride + c] = term ? ch.ray_count : 0u;
    channels.data[CH_NEXT_TRI_TILES * pc.stride + c] = next ? (ch.tri_count + pc.tile_items - 1u) / pc.tile_items : 0u;
    channels.data[CH_NEXT_RAY_TILES * pc.stride + c] = next ? (ch.ray_count + pc.tile_items - 1u) / pc.tile_items : 0u;
}
