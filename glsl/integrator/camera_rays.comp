#version 460
// Primary rays for one chunk of pixels, following the camera convention of
// src/scene/camera.rs: row 0 at the top; through the pixel centre unless jittered.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"
#include "random.glsl"

layout(push_constant) uniform Push {
    FrameParams frame;
    BUFFER_REF(RaysOutRef, rays)
};
BUFFER_BINDING(0, writeonly, Ray, rays)

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    uint pixel = frame.pixel_offset + i;
    uint px = pixel % frame.width;
    uint py = pixel / frame.width;
    vec2 offset = vec2(0.5);
    if (frame.jitter != 0u) {
        offset = vec2(random01(pixel, frame.sample_index, 0u, frame.seed),
                      random01(pixel, frame.sample_index, 1u, frame.seed));
    }
    float sx = 2.0 * (float(px) + offset.x) / float(frame.width) - 1.0;
    float sy = 1.0 - 2.0 * (float(py) + offset.y) / float(frame.height);
    vec3 dir = normalize(frame.forward.xyz + sx * frame.right.xyz + sy * frame.up.xyz);
    rays.data[i] = Ray(frame.origin.xyz, 0.0, dir, 1.0 / 0.0);
}
