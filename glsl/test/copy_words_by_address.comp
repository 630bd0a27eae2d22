#version 460
// dst[first + i] = src[first + i] + add for i < n, with both buffers taken by address
// (glsl/common/address.glsl): the runtime tests' proof that buffers larger than one
// storage binding are read and written whole, and that the descriptor twin runs where
// they fit.
#include "grid.glsl"
#include "address.glsl"
struct CopyPush {
    uint n;
    uint add;
    uint first;
};
layout(push_constant) uniform Push {
    CopyPush pc;
    BUFFER_REF(UintsInRef, src)
    BUFFER_REF(UintsOutRef, dst)
};
BUFFER_BINDING(0, readonly, uint, src)
BUFFER_BINDING(1, writeonly, uint, dst)
void main() {
    uint i = linear_invocation_id();
    if (i < pc.n) dst.data[pc.first + i] = src.data[pc.first + i] + pc.add;
}
