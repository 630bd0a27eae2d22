#version 460
// Stage `sort keys`: the rank of the material key of each live path's hit among the
// scene's keys (src/integrator/pt/materials.rs `sort_ranks`: the keys' order in
// sort_rank_bits bits) and its position, for the radix sort that groups shading work by
// material. A miss writes all ones: its low sort_rank_bits bits exceed every rank, so it
// sorts last.
#include "grid.glsl"
#include "geometry.glsl"
#include "pt.glsl"

layout(push_constant) uniform Push {
    PtParams params;
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(UintsInRef, triangle_material)
    BUFFER_REF(PtMaterialsInRef, materials)
    BUFFER_REF(UintsOutRef, keys)
    BUFFER_REF(UintsOutRef, order)
};
BUFFER_BINDING(0, readonly, Hit, hits)
BUFFER_BINDING(1, readonly, uint, triangle_material)
BUFFER_BINDING(2, readonly, PtMaterial, materials)
BUFFER_BINDING(3, writeonly, uint, keys)
BUFFER_BINDING(4, writeonly, uint, order)

void main() {
    uint i = linear_invocation_id();
    if (i >= params.active_count) return;
    uint tri = hits.data[i].triangle;
    keys.data[i] = tri == MISS ? 0xFFFFFFFFu : materials.data[triangle_material.data[tri]].sort_rank;
    order.data[i] = i;
}
