#version 460
//! variant subgroup: LVC_SUBGROUP_TALLY
// Camera pass, after the shadow rays (Algorithm 8, line 9): each live path's radiance
// gets, in a fixed order, its emitter hit (s = 0), its direct lighting (s = 1) if the
// shadow ray reached the light, and each of its N connections whose shadow ray reached
// the cache vertex. Non-finite contributions are dropped and counted.
//
// The bounce's visibility tally: how many direct-lighting and connection shadow rays
// carried a contribution and how many of them were unoccluded (`VisibilityTally` in
// src/integrator/lvc/gpu.rs): what a resampled selection changes besides the image.
// Summed per subgroup where the device has subgroup arithmetic (the subgroup variant),
// else one atomic per invocation with something to count.
#ifdef LVC_SUBGROUP_TALLY
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#endif
#include "grid.glsl"
#include "geometry.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push { LvcPush P; };
layout(std430, set = 0, binding = 0) readonly buffer Constants { LvcConstants C; };
layout(std430, set = 0, binding = 1) readonly buffer Active { uint live_ids[]; };
layout(std430, set = 0, binding = 2) readonly buffer Emitted { Contribution emitted[]; };
layout(std430, set = 0, binding = 3) readonly buffer ShadowHits { Hit shadow_hits[]; };
layout(std430, set = 0, binding = 4) readonly buffer Contributions { Contribution contrib[]; };
layout(std430, set = 0, binding = 5) buffer Radiance { vec4 radiance[]; };
layout(std430, set = 0, binding = 6) buffer Counters { uint counters[]; };
layout(std430, set = 0, binding = 7) buffer Tally { uint tally[]; };

const uint COUNTER_NON_FINITE = 0u;
const uint TALLY_DIRECT_RAYS = 0u;
const uint TALLY_DIRECT_UNOCCLUDED = 1u;
const uint TALLY_CONNECTION_RAYS = 2u;
const uint TALLY_CONNECTION_UNOCCLUDED = 3u;

void add(inout vec3 sum, Contribution c) {
    if (c.code == CONTRIBUTION_NONE) return;
    if (any(isnan(c.value)) || any(isinf(c.value))) {
        atomicAdd(counters[COUNTER_NON_FINITE], 1u);
        return;
    }
    sum += c.value;
}

// Adds `count` to tally entry `index`; every invocation of the dispatch calls it, in
// uniform control flow (the subgroup variant sums across the subgroup).
void add_tally(uint index, uint count) {
#ifdef LVC_SUBGROUP_TALLY
    uint sum = subgroupAdd(count);
    if (subgroupElect() && sum != 0u) atomicAdd(tally[index], sum);
#else
    if (count != 0u) atomicAdd(tally[index], count);
#endif
}

void main() {
    uint i = linear_invocation_id();
    // (rays, unoccluded) of direct lighting and of the connections.
    uvec2 direct = uvec2(0u);
    uvec2 connections = uvec2(0u);
    if (i < P.active_count) {
        uint c = live_ids[i];
        vec3 sum = radiance[c].rgb;
        add(sum, emitted[i]);
        bool lit = contrib[i].code != CONTRIBUTION_NONE;
        bool open = shadow_hits[i].triangle == MISS;
        direct = uvec2(lit ? 1u : 0u, lit && open ? 1u : 0u);
        if (open) add(sum, contrib[i]);
        for (uint k = 0u; k < C.connections; ++k) {
            uint slot = P.base + i * C.connections + k;
            bool traced = contrib[slot].code != CONTRIBUTION_NONE;
            bool reached = shadow_hits[slot].triangle == MISS;
            connections += uvec2(traced ? 1u : 0u, traced && reached ? 1u : 0u);
            if (reached) add(sum, contrib[slot]);
        }
        radiance[c].rgb = sum;
    }
    add_tally(TALLY_DIRECT_RAYS, direct.x);
    add_tally(TALLY_DIRECT_UNOCCLUDED, direct.y);
    add_tally(TALLY_CONNECTION_RAYS, connections.x);
    add_tally(TALLY_CONNECTION_UNOCCLUDED, connections.y);
}
