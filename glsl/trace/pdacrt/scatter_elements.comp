#version 460
// Next-level index lists, Algorithm 1 lines 12–13: every sorted element is copied into
// the list of each child it belongs to — the next level's list (with the child's new
// node index as its key) or the terminal-node buffer. A "both" element goes to both
// children, a "none" ray to neither. Position = the child's new start + the element's
// offset within the child's range of the sorted parent list (one add: the child's
// route from write_nodes.comp holds new start − source start).
//
// The `ranked` variant (LevelSplit::PrefixSums) takes unsorted lists: the offset within
// the child is the element's rank among its parent's elements on that side (the scanned
// side flags of filter_*.comp), minus the child's source rank (children.comp).
//! variant ranked: RANKED=1
#include "grid.glsl"
#include "pdacrt.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 1) readonly buffer Ids { uint ids[]; };
layout(std430, set = 0, binding = 2) readonly buffer Routes { uvec4 routes[]; };  // write_nodes.comp
layout(std430, set = 0, binding = 3) writeonly buffer NextIds { uint next_ids[]; };
layout(std430, set = 0, binding = 4) writeonly buffer NextKeys { uint next_keys[]; };
layout(std430, set = 0, binding = 5) writeonly buffer TermIds { uint term_ids[]; };
#ifdef RANKED
layout(std430, set = 0, binding = 6) readonly buffer Ranks { uint ranks[]; };
#endif
layout(push_constant) uniform Push {
    uint n;
    uint rays;       // 0: triangle lists, 1: ray lists
    uint left_base;  // ranked: where this list's side ranks start in `ranks`
    uint right_base;
} pc;

void main() {
    uint j = linear_invocation_id();
    if (j >= pc.n) return;
    uint key = keys[j];
    uint node = key >> 2;
    uint code = key & 3u;
    if (code == CODE_NONE) return;
    uint id = ids[j];
    for (uint side = 0u; side < 2u; ++side) {
        if ((side == 0u && code == CODE_RIGHT) || (side == 1u && code == CODE_LEFT)) continue;
        uvec4 route = routes[2u * node + side];
#ifdef RANKED
        uint position = ranks[(side == 0u ? pc.left_base : pc.right_base) + j];
#else
        uint position = j;
#endif
        uint at = position + (pc.rays != 0u ? route.z : route.y);  // wrapping, see Routes
        if (route.x == CHILD_NEXT) {
            next_ids[at] = id;
            next_keys[at] = route.w;
        } else if (route.x == CHILD_TERMINAL) {
            term_ids[at] = id;
        }
    }
}
