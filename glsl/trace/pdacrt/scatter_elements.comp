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

struct ScatterPush {
    uint n;
    uint rays;       // 0: triangle lists, 1: ray lists
    uint left_base;  // ranked: where this list's scanned tile counts start in `ranks`
    uint right_base;
};
layout(push_constant) uniform Push {
    ScatterPush pc;
#ifdef RANKED
    BUFFER_REF(Uvec4sInRef, tiles)
    BUFFER_REF(UintsInRef, ids)
    BUFFER_REF(Uvec4sInRef, routes)  // write_nodes.comp
    BUFFER_REF(UintsOutRef, next_ids)
    BUFFER_REF(UintsOutRef, term_ids)
    BUFFER_REF(UintsInRef, ranks)
#else
    BUFFER_REF(UintsInRef, keys)
    BUFFER_REF(UintsInRef, ids)
    BUFFER_REF(Uvec4sInRef, routes)  // write_nodes.comp
    BUFFER_REF(UintsOutRef, next_ids)
    BUFFER_REF(UintsOutRef, next_keys)
    BUFFER_REF(UintsOutRef, term_ids)
#endif
};
#ifdef RANKED
BUFFER_BINDING(0, readonly, uvec4, tiles)
BUFFER_BINDING(1, readonly, uint, ids)
BUFFER_BINDING(2, readonly, uvec4, routes)
BUFFER_BINDING(3, writeonly, uint, next_ids)
BUFFER_BINDING(4, writeonly, uint, term_ids)
BUFFER_BINDING(5, readonly, uint, ranks)
#else
BUFFER_BINDING(0, readonly, uint, keys)
BUFFER_BINDING(1, readonly, uint, ids)
BUFFER_BINDING(2, readonly, uvec4, routes)
BUFFER_BINDING(3, writeonly, uint, next_ids)
BUFFER_BINDING(4, writeonly, uint, next_keys)
BUFFER_BINDING(5, writeonly, uint, term_ids)
#endif

// Element at `position` (its place in the parent list, or its rank on that side)
// goes where `route` sends it.
void send(uvec4 route, uint position, uint id) {
    uint at = position + (pc.rays != 0u ? route.z : route.y);  // wrapping, see Routes
    if (route.x == CHILD_NEXT) {
        next_ids.data[at] = id;
#ifndef RANKED
        next_keys.data[at] = route.w;
#endif
    } else if (route.x == CHILD_TERMINAL) {
        term_ids.data[at] = id;
    }
}

void main() {
#ifdef RANKED
    uint tile_index = linear_group_id();
    uvec4 tile = tiles.data[tile_index];
    uvec4 left_route = routes.data[2u * tile.x];
    uvec4 right_route = routes.data[2u * tile.x + 1u];
    uint run = (tile.z + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    uint begin = tile.y + min(gl_LocalInvocationID.x * run, tile.z);
    uint end = tile.y + min((gl_LocalInvocationID.x + 1u) * run, tile.z);
    uvec2 counts = uvec2(0u);
    for (uint j = begin; j < end; ++j) counts += side_flags(ids.data[j] >> ID_BITS);
    uvec2 rank = tile_exclusive_scan(counts)
               + uvec2(ranks.data[pc.left_base + tile_index], ranks.data[pc.right_base + tile_index]);
    for (uint j = begin; j < end; ++j) {
        uint raw = ids.data[j];
        uvec2 sides = side_flags(raw >> ID_BITS);
        uint id = raw & ID_MASK;
        if (sides.x != 0u) send(left_route, rank.x, id);
        if (sides.y != 0u) send(right_route, rank.y, id);
        rank += sides;
    }
#else
    uint j = linear_invocation_id();
    if (j >= pc.n) return;
    uint key = keys.data[j];
    uint node = key >> 2;
    uint code = key & 3u;
    uint id = ids.data[j];
    if (code == CODE_LEFT || code == CODE_BOTH) send(routes.data[2u * node], j, id);
    if (code == CODE_RIGHT || code == CODE_BOTH) send(routes.data[2u * node + 1u], j, id);
#endif
}
