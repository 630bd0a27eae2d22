#version 460
// Stage `sort keys`: the material key of each live path's hit (misses sort last) and
// its position, for the radix sort that groups shading work by material.
#include "grid.glsl"
#include "geometry.glsl"
#include "pt.glsl"

layout(push_constant) uniform Push { PtParams params; };
layout(std430, set = 0, binding = 0) readonly buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 1) readonly buffer TriMaterial { uint triangle_material[]; };
layout(std430, set = 0, binding = 2) readonly buffer Materials { PtMaterial materials[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Order { uint order[]; };

void main() {
    uint i = linear_invocation_id();
    if (i >= params.active_count) return;
    uint tri = hits[i].triangle;
    keys[i] = tri == MISS ? 0xFFFFFFFFu : materials[triangle_material[tri]].key;
    order[i] = i;
}
