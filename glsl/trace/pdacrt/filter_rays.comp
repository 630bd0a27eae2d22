#version 460
// Ray filtering, Algorithm 2 lines 2–6: which halves of its node's box the ray's live
// segment meets. The segment ends at the closest hit found so far by earlier flushes
// (Algorithm 1 line 9 updates it), so rays shed nodes beyond their hit; in occlusion
// mode a ray with any hit leaves the hierarchy at once. Boxes and the segment end are
// padded by `eps`, so rounding can only add work, never lose a hit or a tie.
//
// The `ranked` variant (LevelSplit::PrefixSums) works per tile (pdacrt.glsl): one
// workgroup per tile, the node's box and split read once. It keeps the code in the id's
// top bits and writes the tile's side counts — how many of its rays belong to the left
// (right) child — into `ranks` at left_base + tile (right_base + tile). One exclusive
// scan of all count arrays then ranks every tile within its child (see children.comp;
// scatter_elements.comp ranks the elements within their tile). The first workgroup also
// writes the zero counts at n (the tile count) that close each array, so the scan's
// value at n is the array's total.
//
// With `tight` set (PdacrtParams::tight_boxes) the two sides are the children's own
// boxes — their triangles' bounds, which filter_triangles.comp has just written to
// `bounds` — instead of the halves of the node's box: exactly the boxes children.comp
// gives the children, padded by eps as the next level pads its node's box. A ray that
// meets a half but not the triangles in it leaves now instead of one level later, and
// a side without triangles takes no rays.
//! variant ranked: RANKED=1
#include "grid.glsl"
#include "geometry.glsl"
#include "pdacrt.glsl"
#ifdef RANKED
#include "tile_lanes.glsl"
#endif

// Rays and nodes are read through vec4 views (two and three vec4 per record): CPU
// devices turn every lane's load into a scalar loop, so one 16-byte load beats four
// 4-byte ones.
layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer BestInRef { uvec2 data[]; };
struct FilterRaysPush {
    uint n;  // list length (ranked: the tile count, also the dispatch size)
    float eps;
    uint occlusion;
    uint ray_offset;
    uint left_base;
    uint right_base;
    uint tight;  // 1: test against the children's triangle bounds in `bounds`
    uint hits_written;  // 0: no flush has written a closest hit yet, all are "none"
};
layout(push_constant) uniform Push {
    FilterRaysPush pc;
    BUFFER_REF(Vec4sInRef, rays4)
    BUFFER_REF(Vec4sInRef, nodes4)
#ifdef RANKED
    BUFFER_REF(UintsRef, ids)
    BUFFER_REF(Uvec4sInRef, tiles)
#else
    BUFFER_REF(UintsInRef, ids)
    BUFFER_REF(UintsRef, keys)
#endif
    // The hit buffer, holding the closest hits so far (BEST_SLOT in pdacrt.glsl).
    BUFFER_REF(BestInRef, best)
#ifdef RANKED
    BUFFER_REF(UintsOutRef, ranks)
#endif
    BUFFER_REF(UintsInRef, bounds)
};
BUFFER_BINDING(0, restrict readonly, vec4, rays4)
BUFFER_BINDING(1, restrict readonly, vec4, nodes4)
#ifdef RANKED
BUFFER_BINDING(2, restrict, uint, ids)
BUFFER_BINDING(3, restrict readonly, uvec4, tiles)
#else
BUFFER_BINDING(2, restrict readonly, uint, ids)
BUFFER_BINDING(3, restrict, uint, keys)
#endif
BUFFER_BINDING(4, restrict readonly, uvec2, best)
#ifdef RANKED
BUFFER_BINDING(5, restrict writeonly, uint, ranks)
BUFFER_BINDING(6, restrict readonly, uint, bounds)
#else
BUFFER_BINDING(5, restrict readonly, uint, bounds)
#endif

// The two boxes a node's rays are sorted into (line 4), padded by eps; a side without
// a box takes no rays.
struct Sides {
    vec3 lo[2];
    vec3 hi[2];
    bool present[2];
};

// The paper's sides: the halves of the node's box.
Sides halves(vec3 box_min, vec3 box_max) {
    vec3 lo = box_min - pc.eps;
    vec3 hi = box_max + pc.eps;
    uint axis = split_axis(box_min, box_max);
    bvec3 on_axis = axis_mask(axis);
    float mid = split_position(box_min, box_max, axis);
    vec3 left_hi = mix(hi, vec3(mid + pc.eps), on_axis);
    vec3 right_lo = mix(lo, vec3(mid - pc.eps), on_axis);
    return Sides(vec3[2](lo, right_lo), vec3[2](left_hi, hi), bool[2](true, true));
}

// Tight sides: the boxes of node `node`'s children (children.comp), padded by eps.
Sides child_boxes(uint node) {
    Sides s;
    for (uint side = 0u; side < 2u; ++side) {
        uint w = 8u * (2u * node + side);
        s.present[side] = has_child_bounds(bounds.data[w]);
        s.lo[side] = child_bounds_min(uvec3(bounds.data[w], bounds.data[w + 1u], bounds.data[w + 2u])) - pc.eps;
        s.hi[side] = child_bounds_max(uvec3(bounds.data[w + 4u], bounds.data[w + 5u], bounds.data[w + 6u])) + pc.eps;
    }
    return s;
}

Sides node_sides(uint node) {
    if (pc.tight != 0u) return child_boxes(node);
    return halves(nodes4.data[3u * node].xyz, nodes4.data[3u * node + 1u].xyz);  // Node.box_min, box_max
}

// The status code of ray `id` against the node's two sides (lines 4–5).
uint ray_code(uint id, Sides sides) {
    // Before the chunk's first flush every closest hit is the initial "none" (all
    // ones): one gather per ray saved on the levels above it.
    uvec2 closest = pc.hits_written != 0u ? best.data[BEST_SLOT(pc.ray_offset + id)] : uvec2(0xFFFFFFFFu);
    if (pc.occlusion != 0u && has_hit(closest)) return CODE_NONE;
    vec4 origin_tmin = rays4.data[2u * (pc.ray_offset + id)];
    vec4 dir_tmax = rays4.data[2u * (pc.ray_offset + id) + 1u];
    Ray r = Ray(origin_tmin.xyz, origin_tmin.w, dir_tmax.xyz, dir_tmax.w);
    // An empty segment meets no triangle; left in, it would pass the box tests of every
    // node around its origin down to a leaf and be brute-forced there.
    if (ray_is_empty(r)) return CODE_NONE;
    float t1 = min(r.tmax, hit_t(closest) + pc.eps);
    bvec3 parallel = equal(r.dir, vec3(0.0));
    vec3 inv = 1.0 / mix(r.dir, vec3(1.0), parallel);
    bool left = sides.present[0] && ray_meets_box_inv(r.origin, inv, parallel, r.tmin, t1, sides.lo[0], sides.hi[0]);
    bool right = sides.present[1] && ray_meets_box_inv(r.origin, inv, parallel, r.tmin, t1, sides.lo[1], sides.hi[1]);
    return (left && right) ? CODE_BOTH : (left ? CODE_LEFT : (right ? CODE_RIGHT : CODE_NONE));
}

void main() {
#ifdef RANKED
    uint tile_index = linear_group_id();
    uvec4 tile = tiles.data[tile_index];
    uint lid = gl_LocalInvocationID.x;
    Sides sides = node_sides(tile.x);
    uvec2 counts = uvec2(0u);
    for (uint k = lid; k < tile.z; k += WORKGROUP_SIZE) {
        uint i = tile.y + k;
        uint id = ids.data[i] & ID_MASK;
        uint code = ray_code(id, sides);
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
    uint code = ray_code(ids.data[i], node_sides(node));
    keys.data[i] = (node << 2) | code;
#endif
}
