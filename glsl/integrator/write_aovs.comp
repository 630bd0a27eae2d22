#version 460
// First-hit AOVs of a chunk: depth (distance along the unit ray; +inf on a miss), the
// triangle index (0xFFFFFFFF on a miss) and the viewer-facing geometric normal.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"

layout(push_constant) uniform Push { FrameParams frame; };
layout(std430, set = 0, binding = 0) readonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 1) readonly buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 2) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Depth { float depth[]; };
layout(std430, set = 0, binding = 4) writeonly buffer TriId { uint triangle_id[]; };
layout(std430, set = 0, binding = 5) writeonly buffer Normal { vec4 normal[]; };

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    uint pixel = frame.pixel_offset + i;
    Hit hit = hits[i];
    vec3 n = vec3(0.0);
    if (hit.triangle != MISS) {
        Triangle tri = triangles[hit.triangle];
        n = normalize(cross(tri.e1.xyz, tri.e2.xyz));
        if (dot(n, rays[i].dir) > 0.0) n = -n;
    }
    depth[pixel] = hit.t;
    triangle_id[pixel] = hit.triangle;
    normal[pixel] = vec4(n, 0.0);
}
