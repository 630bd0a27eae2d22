#version 460
// Eye-light shading of primary hits: emitted radiance plus albedo × |cos| between the
// geometric normal and the view ray, as if a light sat at the eye. Accumulates into the
// film's running sum.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"
#include "film_sum.glsl"
#include "material.glsl"

layout(push_constant) uniform Push {
    FrameParams frame;
    BUFFER_REF(RaysInRef, rays)
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(UintsInRef, triangle_material)
    BUFFER_REF(MaterialsInRef, materials)
    BUFFER_REF(Vec4sRef, accum)
};
BUFFER_BINDING(0, readonly, Ray, rays)
BUFFER_BINDING(1, readonly, Hit, hits)
BUFFER_BINDING(2, readonly, Triangle, triangles)
BUFFER_BINDING(3, readonly, uint, triangle_material)
BUFFER_BINDING(4, readonly, Material, materials)
BUFFER_BINDING(5, , vec4, accum)

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    uint pixel = frame.pixel_offset + i;
    Hit hit = hits.data[i];
    vec3 color = vec3(0.0);
    if (hit.triangle != MISS) {
        Triangle tri = triangles.data[hit.triangle];
        vec3 n = normalize(triangle_normal(tri));
        Material m = materials.data[triangle_material.data[hit.triangle]];
        color = m.emission.rgb + m.diffuse.rgb * abs(dot(n, rays.data[i].dir));
    }
    FILM_ADD(accum.data, pixel, frame.width * frame.height, vec4(color, 1.0));
}
