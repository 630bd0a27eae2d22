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

#include "children.glsl"

void main() {
    uint c = linear_invocation_id();
    if (c < pc.child_count) write_child(c);
}
