// Records and helpers shared by the PDACRT kernels (src/trace/pdacrt/ is the host side,
// with the same layouts in src/trace/pdacrt/types.rs).
//
// Status codes (paper §2.1 encodes left/both/right/none as 1/2/3/4 in "the right-most 2
// bits", which cannot hold 4; we use 0/1/2/3 so they fit and still sort as
// left < both < right < none, which keeps the pivot property of Figure 4: the left
// child's range is [left, both], the right child's [both, right]).
#ifndef SPLITRAY_PDACRT_GLSL
#define SPLITRAY_PDACRT_GLSL

#include "geometry.glsl"

#define CODE_LEFT 0u
#define CODE_BOTH 1u
#define CODE_RIGHT 2u
#define CODE_NONE 3u

#define CHILD_DROPPED 0u
#define CHILD_NEXT 1u
#define CHILD_TERMINAL 2u

// Channels of the per-child arrays that are prefix-summed each level.
#define CH_NEXT_FLAG 0u
#define CH_NEXT_TRIS 1u
#define CH_NEXT_RAYS 2u
#define CH_TERM_FLAG 3u
#define CH_TERM_TRIS 4u
#define CH_TERM_RAYS 5u
#define CH_NEXT_TRI_TILES 6u
#define CH_NEXT_RAY_TILES 7u
#define CHANNELS 8u

// Tiles (LevelSplit::PrefixSums): a level's lists are cut into tiles of at most
// `tile_items` elements of one node, (node, first element, count, 0), one workgroup
// each. The node is then uniform in the workgroup: its box and routes are loaded once
// per tile instead of once per element, and no per-element key names it.
// The ranked kernels also keep each element's status code in the top two bits of its
// id (ids stay below 2^30: see PdacrtTracer::with_params).
#define ID_BITS 30u
#define ID_MASK ((1u << ID_BITS) - 1u)

// Exclusive prefix sum of channel `k` at child `c`, from the one scan that runs through
// all channels back to back (`offsets`, `stride` words per channel): the scan's value at
// the channel's first child is everything before the channel. Wrapping subtraction, so
// the padding after each channel's children may hold anything.
#define CHANNEL_OFFSET(offsets, stride, k, c) ((offsets)[(k) * (stride) + (c)] - (offsets)[(k) * (stride)])

// A node of the implicit hierarchy: its box and its pivots (start, count) into the
// level's triangle and ray id lists; with LevelSplit::PrefixSums also its first tile in
// each list (a node's lists are cut into consecutive tiles), else zero.
struct Node {
    vec3 box_min;
    uint first_tri_tile;
    vec3 box_max;
    uint first_ray_tile;
    uint tri_start;
    uint tri_count;
    uint ray_start;
    uint ray_count;
};

// One child of a node after filtering (two per node: left = 2p, right = 2p + 1).
struct Child {
    vec4 box_min;
    vec4 box_max;
    uint kind;       // CHILD_DROPPED / CHILD_NEXT / CHILD_TERMINAL
    uint tri_src;    // first of its triangles in the parent's sorted triangle list
    uint tri_count;
    uint ray_src;    // first of its rays in the parent's sorted ray list
    uint ray_count;
    uint pad0;
    uint pad1;
    uint pad2;
};

// What children.glsl decides a level's children by (ChildrenPush in kernels.rs).
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

// A terminal node in the terminal-node buffer: ranges of its triangle and ray ids.
struct Segment {
    uint tri_start;
    uint tri_count;
    uint ray_start;
    uint ray_count;
};

// The records by device address (address.glsl): a level's lists grow with the scene.
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer NodesInRef { Node data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer NodesOutRef { Node data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer ChildrenInRef { Child data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer ChildrenOutRef { Child data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer SegmentsInRef { Segment data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer SegmentsOutRef { Segment data[]; };

// Order-preserving map of float bits to uint (negative floats reversed below the
// positive ones), so that comparing the uints compares the floats.
uint ordered_bits(float t) {
    uint b = floatBitsToUint(t);
    return (b & 0x80000000u) != 0u ? ~b : (b | 0x80000000u);
}

float from_ordered_bits(uint o) {
    return uintBitsToFloat((o & 0x80000000u) != 0u ? (o & 0x7FFFFFFFu) : ~o);
}

// A child's tight box (PdacrtParams::tight_boxes) from its eight words in the level's
// bounds buffer (filter_triangles.comp): min.xyz as order-preserving bits, then ~max.xyz
// from word 4. `min_x_bits` all ones means that no triangle reached the child.
bool has_child_bounds(uint min_x_bits) {
    return min_x_bits != 0xFFFFFFFFu;
}

vec3 child_bounds_min(uvec3 bits) {
    return vec3(from_ordered_bits(bits.x), from_ordered_bits(bits.y), from_ordered_bits(bits.z));
}

vec3 child_bounds_max(uvec3 inverted_bits) {
    return child_bounds_min(~inverted_bits);
}

// The chunk's global closest hits (the paper's mints and hitid, Algorithm 1 line 9), one
// uvec2 per ray: (triangle, ordered_bits(t)). Read as a uint64 it is
// ordered_bits(t) << 32 | triangle, so one 64-bit atomicMin keeps the smaller t and,
// for equal t, the smaller triangle (segmented_intersect.comp, atomic variants). The
// initial all-ones value is above every hit and means no hit yet.
//
// They live in the caller's hit buffer, not in memory of their own (peak memory): ray
// i's pair is the first 8 bytes of its 16-byte hit record, that is uvec2 (or uint64)
// element BEST_SLOT(i) of the buffer, until finalize_hits.comp turns each into the hit
// record in place. `i` counts from the batch's first ray, not the chunk's.
#define BEST_SLOT(i) (2u * (i))
bool has_hit(uvec2 best) {
    return best.x != MISS;
}

float hit_t(uvec2 best) {
    return has_hit(best) ? from_ordered_bits(best.y) : 1.0 / 0.0;
}

// The split of Algorithm 2 line 4: the midpoint of the box's largest extent.
uint split_axis(vec3 lo, vec3 hi) {
    vec3 e = hi - lo;
    return (e.x >= e.y && e.x >= e.z) ? 0u : (e.y >= e.z ? 1u : 2u);
}

// v[axis] by selects: CPU devices may lower dynamic component indexing to a local
// array in memory.
float component(vec3 v, uint axis) {
    return axis == 0u ? v.x : (axis == 1u ? v.y : v.z);
}

float split_position(vec3 lo, vec3 hi, uint axis) {
    return 0.5 * component(lo + hi, axis);
}

// The split axis as a component mask, for selects instead of dynamic component indexing
// (which CPU devices may lower to a local array in memory).
bvec3 axis_mask(uint axis) {
    return equal(uvec3(axis), uvec3(0u, 1u, 2u));
}

// Whether the segment [t0, t1] of the ray meets the closed box [lo, hi], with the
// reciprocal direction precomputed. Axes the ray runs parallel to (d == 0) are tested by
// the origin alone; the select discards their NaN or infinite slab distances.
bool ray_meets_box_inv(vec3 o, vec3 inv, bvec3 parallel, float t0, float t1, vec3 lo, vec3 hi) {
    vec3 ta = (lo - o) * inv;
    vec3 tb = (hi - o) * inv;
    vec3 near = mix(min(ta, tb), vec3(-1.0 / 0.0), parallel);
    vec3 far = mix(max(ta, tb), vec3(1.0 / 0.0), parallel);
    bool outside = any(bvec3(uvec3(parallel) & (uvec3(lessThan(o, lo)) | uvec3(greaterThan(o, hi)))));
    float enter = max(t0, max(near.x, max(near.y, near.z)));
    float leave = min(t1, min(far.x, min(far.y, far.z)));
    return !outside && enter <= leave;
}

#endif
