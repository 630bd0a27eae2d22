#version 460
// Stage `compact` (second half): moves the surviving paths' rays and ids to the front,
// in their original order, so the next bounce traces a dense batch.
#include "grid.glsl"
#include "geometry.glsl"
#include "pt.glsl"

layout(push_constant) uniform Push { PtParams params; };
layout(std430, set = 0, binding = 0) readonly buffer Kept { uint kept[]; };
layout(std430, set = 0, binding = 1) readonly buffer RaysIn { Ray rays_in[]; };
layout(std430, set = 0, binding = 2) readonly buffer ActiveIn { uint ids_in[]; };
layout(std430, set = 0, binding = 3) writeonly buffer RaysOut { Ray rays_out[]; };
layout(std430, set = 0, binding = 4) writeonly buffer ActiveOut { uint ids_out[]; };

void main() {
    uint k = linear_invocation_id();
    if (k >= params.active_count) return;
    uint i = kept[k];
    rays_out[k] = rays_in[i];
    ids_out[k] = ids_in[i];
}
