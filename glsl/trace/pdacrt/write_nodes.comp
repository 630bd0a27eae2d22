#version 460
// Next-level nodes and terminal segments, Algorithm 1 lines 13–14: each surviving child
// becomes a node of the next level (pivots re-indexed by the prefix sums, so terminal
// and dropped children leave no gaps) or segments of the terminal-node buffer. A
// terminal node with more than max_segment_rays rays is split into segments of at most
// that many rays over the same triangles: Algorithm 3 gives each segment one workgroup,
// and the paper's N-thread blocks assume nodes below β rays — a node that is terminal
// for its few triangles may hold a whole image's rays (the root of a small scene does),
// which one workgroup would trace alone.
//
// The `ranked` variant (LevelSplit::PrefixSums) also cuts each next-level node's lists
// into tiles (pdacrt.glsl) for the next level's filters and scatter.
//! variant ranked: RANKED=1
#include "grid.glsl"
#include "pdacrt.glsl"

layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer Uvec4sOutRef { uvec4 data[]; };
struct WriteNodesPush {
    uint child_count;
    uint stride;
    uint segment_base;
    uint term_tri_base;
    uint term_ray_base;
    uint max_segment_rays;
    uint tile_items;
};
layout(push_constant) uniform Push {
    WriteNodesPush pc;
    BUFFER_REF(ChildrenInRef, children)
    BUFFER_REF(UintsInRef, offsets)
    BUFFER_REF(NodesOutRef, next_nodes)
    BUFFER_REF(SegmentsOutRef, segments)
    // Per child, where scatter_elements.comp sends its elements: (kind, triangle delta,
    // ray delta, next-level key). An element's destination is its position in the parent
    // list (or its rank, ranked) plus the delta — the child's destination start minus its
    // source start, wrapping — so the scatter reads 4 words per child instead of the
    // child record and three prefix sums.
    BUFFER_REF(Uvec4sOutRef, routes)
#ifdef RANKED
    BUFFER_REF(Uvec4sOutRef, tri_tiles)
    BUFFER_REF(Uvec4sOutRef, ray_tiles)
#endif

};
BUFFER_BINDING(0, readonly, Child, children)
BUFFER_BINDING(1, readonly, uint, offsets)
BUFFER_BINDING(2, writeonly, Node, next_nodes)
BUFFER_BINDING(3, writeonly, Segment, segments)
BUFFER_BINDING(4, writeonly, uvec4, routes)
#ifdef RANKED
BUFFER_BINDING(5, writeonly, uvec4, tri_tiles)
BUFFER_BINDING(6, writeonly, uvec4, ray_tiles)
#endif

void main() {
    uint c = linear_invocation_id();
    if (c >= pc.child_count) return;
    Child ch = children.data[c];
    uvec4 route = uvec4(ch.kind, 0u, 0u, 0u);
    if (ch.kind == CHILD_NEXT) {
        uint node = CHANNEL_OFFSET(offsets.data, pc.stride, CH_NEXT_FLAG, c);
        uint tri_start = CHANNEL_OFFSET(offsets.data, pc.stride, CH_NEXT_TRIS, c);
        uint ray_start = CHANNEL_OFFSET(offsets.data, pc.stride, CH_NEXT_RAYS, c);
        route = uvec4(ch.kind, tri_start - ch.tri_src, ray_start - ch.ray_src, node << 2);
#ifdef RANKED
        uint first_tri_tile = CHANNEL_OFFSET(offsets.data, pc.stride, CH_NEXT_TRI_TILES, c);
        uint first_ray_tile = CHANNEL_OFFSET(offsets.data, pc.stride, CH_NEXT_RAY_TILES, c);
#else
        uint first_tri_tile = 0u;
        uint first_ray_tile = 0u;
#endif
        next_nodes.data[node] = Node(ch.box_min.xyz, first_tri_tile, ch.box_max.xyz, first_ray_tile,
                                tri_start, ch.tri_count, ray_start, ch.ray_count);
#ifdef RANKED
        uint tile = first_tri_tile;
        for (uint done = 0u; done < ch.tri_count; done += pc.tile_items) {
            tri_tiles.data[tile++] = uvec4(node, tri_start + done, min(pc.tile_items, ch.tri_count - done), 0u);
        }
        tile = first_ray_tile;
        for (uint done = 0u; done < ch.ray_count; done += pc.tile_items) {
            ray_tiles.data[tile++] = uvec4(node, ray_start + done, min(pc.tile_items, ch.ray_count - done), 0u);
        }
#endif
    } else if (ch.kind == CHILD_TERMINAL) {
        uint first = pc.segment_base + CHANNEL_OFFSET(offsets.data, pc.stride, CH_TERM_FLAG, c);
        uint tri_start = pc.term_tri_base + CHANNEL_OFFSET(offsets.data, pc.stride, CH_TERM_TRIS, c);
        uint ray_start = pc.term_ray_base + CHANNEL_OFFSET(offsets.data, pc.stride, CH_TERM_RAYS, c);
        route = uvec4(ch.kind, tri_start - ch.tri_src, ray_start - ch.ray_src, 0u);
        for (uint done = 0u, k = 0u; done < ch.ray_count; done += pc.max_segment_rays, ++k) {
            segments.data[first + k] = Segment(tri_start, ch.tri_count, ray_start + done,
                                          min(pc.max_segment_rays, ch.ray_count - done));
        }
    }
    routes.data[c] = route;
}
