#version 460
// Light pass (Algorithm 7, line 7): the vertices marked this bounce go to the cache at
// base + their rank among the marked ones (compaction of the marks: the active-list
// order, so the cache's content is the same on every device). A slot past the capacity
// is not written: the host sees the count, grows the cache and runs the pass again, so
// no vertex is ever dropped or overwritten.
#include "grid.glsl"
#include "geometry.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push { LvcPush P; };
layout(std430, set = 0, binding = 0) readonly buffer Kept { uint kept[]; };
layout(std430, set = 0, binding = 1) readonly buffer Count { uint marked; };
layout(std430, set = 0, binding = 2) readonly buffer VertexOut { LvcVertex vertex_out[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Cache { LvcVertex cache[]; };

void main() {
    uint k = linear_invocation_id();
    if (k >= P.active_count || k >= marked) return;
    uint slot = P.base + k;
    if (slot >= P.capacity) return;
    cache[slot] = vertex_out[kept[k]];
}
