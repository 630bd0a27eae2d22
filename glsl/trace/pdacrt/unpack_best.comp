#version 460
// FlushReduce::AtomicMin, Algorithm 1 line 9: after a flush has atomically lowered each
// ray's packed closest hit (segmented_intersect.comp, `atomic` variants), unpack it into
// the global t and triangle arrays that ray filtering and the final hits read. A ray
// with no hit yet keeps its all-ones initial value and stays (+inf, MISS). The packed
// value only ever decreases, so unpacking after every flush is exact.
#include "grid.glsl"
#include "geometry.glsl"
#include "pdacrt.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Best { uvec2 best_packed[]; };  // (tri, ordered t)
layout(std430, set = 0, binding = 1) writeonly buffer BestT { float best_t[]; };
layout(std430, set = 0, binding = 2) writeonly buffer BestTri { uint best_tri[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    uvec2 p = best_packed[i];
    bool hit = p.x != MISS;
    best_t[i] = hit ? from_ordered_bits(p.y) : 1.0 / 0.0;
    best_tri[i] = p.x;
}
