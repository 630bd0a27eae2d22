#version 460
// ids[i] = base + i and tags[i] = tag for i < n: the root's index lists (Algorithm 1
// line 2) and the value lists sorted alongside keys.
// The `ids_only` variant writes no tags (tiled levels have no keys).
//! variant ids_only: IDS_ONLY=1
#include "grid.glsl"
layout(std430, set = 0, binding = 0) writeonly buffer Ids { uint ids[]; };
#ifndef IDS_ONLY
layout(std430, set = 0, binding = 1) writeonly buffer Tags { uint tags[]; };
#endif
layout(push_constant) uniform Push { uint n; uint base; uint tag; } pc;
void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    ids[i] = pc.base + i;
#ifndef IDS_ONLY
    tags[i] = pc.tag;
#endif
}
