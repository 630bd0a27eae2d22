// Children of a level, shared by children.comp (one invocation per child) and
// level_plan.comp (one workgroup for the whole level): see children.comp. The including
// kernel declares `pc` (a ChildrenPush) and the buffers nodes, ranks (RANKED) or
// tri_counts and ray_counts, children, channels and bounds.
#ifndef SPLITRAY_CHILDREN_GLSL
#define SPLITRAY_CHILDREN_GLSL

// Whether a child has too few rays to split (the β test, Algorithm 1 line 6). With a
// `terminal_cost` (PdacrtParams::terminal_cost) a child below β rays still splits while
// its brute force would cost that many ray-triangle tests or more: a handful of rays
// over thousands of triangles goes on down.
bool few_rays(uint rays, uint tris) {
    return rays < pc.beta && (pc.terminal_cost == 0u || float(rays) * float(tris) < float(pc.terminal_cost));
}

void write_child(uint c) {
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

#endif
