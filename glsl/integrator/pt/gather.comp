#version 460
// Stage `compact` (second half): moves the surviving paths' rays and ids to the front,
// in their original order, so the next bounce traces a dense batch.
#include "grid.glsl"
#include "geometry.glsl"
#include "pt.glsl"

layout(push_constant) uniform Push {
    PtParams params;
    BUFFER_REF(UintsInRef, kept)
    BUFFER_REF(RaysInRef, rays_in)
    BUFFER_REF(UintsInRef, ids_in)
    BUFFER_REF(RaysOutRef, rays_out)
    BUFFER_REF(UintsOutRef, ids_out)
};
BUFFER_BINDING(0, readonly, uint, kept)
BUFFER_BINDING(1, readonly, Ray, rays_in)
BUFFER_BINDING(2, readonly, uint, ids_in)
BUFFER_BINDING(3, writeonly, Ray, rays_out)
BUFFER_BINDING(4, writeonly, uint, ids_out)

void main() {
    uint k = linear_invocation_id();
    if (k >= params.active_count) return;
    uint i = kept.data[k];
    rays_out.data[k] = rays_in.data[i];
    ids_out.data[k] = ids_in.data[i];
}
