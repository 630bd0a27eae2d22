#version 460
// ids[i] = base + i and tags[i] = tag for i < n: the root's index lists (Algorithm 1
// line 2) and the value lists sorted alongside keys.
// The `ids_only` variant writes no tags (tiled levels have no keys).
//! variant ids_only: IDS_ONLY=1
#include "grid.glsl"
#include "address.glsl"
struct IotaPush {
    uint n;
    uint base;
    uint tag;
};
layout(push_constant) uniform Push {
    IotaPush pc;
    BUFFER_REF(UintsOutRef, ids)
#ifndef IDS_ONLY
    BUFFER_REF(UintsOutRef, tags)
#endif
};
BUFFER_BINDING(0, writeonly, uint, ids)
#ifndef IDS_ONLY
BUFFER_BINDING(1, , uint, tags)
#endif
void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    ids.data[i] = pc.base + i;
#ifndef IDS_ONLY
    tags.data[i] = pc.tag;
#endif
}
