#version 460
// Next-level index lists, Algorithm 1 lines 12–13: every sorted element is copied into
// the list of each child it belongs to — the next level's list (with the child's new
// node index as its key) or the terminal-node buffer. A "both" element goes to both
// children, a "none" ray to neither. Position = the child's new start + the element's
// offset within the child's range of the sorted parent list (one add: the child's
// route from write_nodes.comp holds new start − source start).
//
// The `ranked` variant (LevelSplit::PrefixSums) takes unsorted lists, per tile: the
// node and its two routes are read once per tile, the code comes from the id's top bits
// (filter_*.comp), and the offset within the child is the element's rank among its
// parent's elements on that side, minus the child's source rank (children.comp). That
// rank is the tile's (the scanned tile counts) plus the element's within the tile: each
// invocation takes a contiguous run of the tile, counts its run's sides, and the
// workgroup scans the counts (tile_lanes.glsl), so the child lists keep the parent's
// order. The next level needs no keys: its tiles name the nodes.
//! variant ranked: RANKED=1
#include "grid.glsl"
#include "pdacrt.glsl"
#ifdef RANKED
#include "tile_lanes.glsl"
#endif

#ifdef RANKED
layout(std430, set = 0, binding = 0) readonly buffer Tiles { uvec4 tiles[]; };
layout(std430, set = 0, binding = 1) readonly buffer Ids { uint ids[]; };
layout(std430, set = 0, binding = 2) readonly buffer Routes { uvec4 routes[]; };  // write_nodes.comp
layout(std430, set = 0, binding = 3) writeonly buffer NextIds { uint next_ids[]; };
layout(std430, set = 0, binding = 4) writeonly buffer TermIds { uint term_ids[]; };
layout(std430, set = 0, binding = 5) readonly buffer Ranks { uint ranks[]; };
#else
layout(std430, set = 0, binding = 0) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 1) readonly buffer Ids { uint ids[]; };
layout(std430, set = 0, binding = 2) readonly buffer Routes { uvec4 routes[]; };  // write_nodes.comp
layout(std430, set = 0, binding = 3) writeonly buffer NextIds { uint next_ids[]; };
layout(std430, set = 0, binding = 4) writeonly buffer NextKeys { uint next_keys[]; };
layout(std430, set = 0, binding = 5) writeonly buffer TermIds { uint term_ids[]; };
#endif
layout(push_constant) uniform Push {
    uint n;
    uint rays;       // 0: triangle lists, 1: ray lists
    uint left_base;  // ranked: where this list's scanned tile counts start in `ranks`
    uint right_base;
} pc;

// Element at `position` (its place in the parent list, or its rank on that side)
// goes where `route` sends it.
void send(uvec4 route, uint position, uint id) {
    uint at = position + (pc.rays != 0u ? route.z : route.y);  // wrapping, see Routes
    if (route.x == CHILD_NEXT) {
        next_ids[at] = id;
#ifndef RANKED
        next_keys[at] = route.w;
#endif
    } else if (route.x == CHILD_TERMINAL) {
        term_ids[at] = id;
    }
}

void main() {
#ifdef RANKED
    uint tile_index = linear_group_id();
    uvec4 tile = tiles[tile_index];
    uvec4 left_route = routes[2u * tile.x];
    uvec4 right_route = routes[2u * tile.x + 1u];
    uint run = (tile.z + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    uint begin = tile.y + min(gl_LocalInvocationID.x * run, tile.z);
    uint end = tile.y + min((gl_LocalInvocationID.x + 1u) * run, tile.z);
    uvec2 counts = uvec2(0u);
    for (uint j = begin; j < end; ++j) counts += side_flags(ids[j] >> ID_BITS);
    uvec2 rank = tile_exclusive_scan(counts)
               + uvec2(ranks[pc.left_base + tile_index], ranks[pc.right_base + tile_index]);
    for (uint j = begin; j < end; ++j) {
        uint raw = ids[j];
        uvec2 sides = side_flags(raw >> ID_BITS);
        uint id = raw & ID_MASK;
        if (sides.x != 0u) send(left_route, rank.x, id);
        if (sides.y != 0u) send(right_route, rank.y, id);
        rank += sides;
    }
#else
    uint j = linear_invocation_id();
    if (j >= pc.n) return;
    uint key = keys[j];
    uint node = key >> 2;
    uint code = key & 3u;
    uint id = ids[j];
    if (code == CODE_LEFT || code == CODE_BOTH) send(routes[2u * node], j, id);
    if (code == CODE_RIGHT || code == CODE_BOTH) send(routes[2u * node + 1u], j, id);
#endif
}
