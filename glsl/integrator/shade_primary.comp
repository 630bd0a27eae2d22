#version 460
// Eye-light shading of primary hits: emitted radiance plus albedo × |cos| between the
// geometric normal and the view ray, as if a light sat at the eye. Accumulates into the
// film's running sum.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"
#include "material.glsl"

layout(push_constant) uniform Push { FrameParams frame; };
layout(std430, set = 0, binding = 0) readonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 1) readonly buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 2) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 3) readonly buffer TriMaterial { uint triangle_material[]; };
layout(std430, set = 0, binding = 4) readonly buffer Materials { Material materials[]; };
layout(std430, set = 0, binding = 5) buffer Accum { vec4 accum[]; };

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    uint pixel = frame.pixel_offset + i;
    Hit hit = hits[i];
    vec3 color = vec3(0.0);
    if (hit.triangle != MISS) {
        Triangle tri = triangles[hit.triangle];
        vec3 n = normalize(cross(tri.e1.xyz, tri.e2.xyz));
        Material m = materials[triangle_material[hit.triangle]];
        color = m.emission.rgb + m.diffuse.rgb * abs(dot(n, rays[i].dir));
    }
    accum[pixel] += vec4(color, 1.0);
}
