#version 460
// First-hit AOVs of a chunk: depth (distance along the unit ray; +inf on a miss), the
// triangle index (0xFFFFFFFF on a miss) and the viewer-facing geometric normal.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"

layout(push_constant) uniform Push {
    FrameParams frame;
    BUFFER_REF(RaysInRef, rays)
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(FloatsOutRef, depth)
    BUFFER_REF(UintsOutRef, triangle_id)
    BUFFER_REF(Vec4sOutRef, normal)
};
BUFFER_BINDING(0, readonly, Ray, rays)
BUFFER_BINDING(1, readonly, Hit, hits)
BUFFER_BINDING(2, readonly, Triangle, triangles)
BUFFER_BINDING(3, writeonly, float, depth)
BUFFER_BINDING(4, writeonly, uint, triangle_id)
BUFFER_BINDING(5, writeonly, vec4, normal)

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    uint pixel = frame.pixel_offset + i;
    Hit hit = hits.data[i];
    vec3 n = vec3(0.0);
    if (hit.triangle != MISS) {
        Triangle tri = triangles.data[hit.triangle];
        n = normalize(triangle_normal(tri));
        if (dot(n, rays.data[i].dir) > 0.0) n = -n;
    }
    depth.data[pixel] = hit.t;
    triangle_id.data[pixel] = hit.triangle;
    normal.data[pixel] = vec4(n, 0.0);
}
