#version 460
// Stage `generate`: a fresh path per pixel of the chunk, its camera ray (uniformly
// jittered in the pixel: a box filter) and the identity active list.
#include "grid.glsl"
#include "geometry.glsl"
#include "random.glsl"
#include "pt.glsl"

layout(push_constant) uniform Push {
    PtParams params;
    BUFFER_REF(RaysOutRef, rays)
    BUFFER_REF(UintsOutRef, live_ids)
    BUFFER_REF(PathStatesOutRef, paths)
};
BUFFER_BINDING(0, writeonly, Ray, rays)
BUFFER_BINDING(1, writeonly, uint, live_ids)
BUFFER_BINDING(2, writeonly, PathState, paths)

void main() {
    uint i = linear_invocation_id();
    if (i >= params.path_count) return;
    uint pixel = pt_pixel(params, i);
    uint sample_index = pt_sample(params, i);
    uint px = pixel % params.width;
    uint py = pixel / params.width;
    vec2 offset = vec2(random01(pixel, sample_index, 0u, params.seed),
                       random01(pixel, sample_index, 1u, params.seed));
    float sx = 2.0 * (float(px) + offset.x) / float(params.width) - 1.0;
    float sy = 1.0 - 2.0 * (float(py) + offset.y) / float(params.height);
    vec3 dir = normalize(params.forward.xyz + sx * params.right.xyz + sy * params.up.xyz);
    rays.data[i] = Ray(params.origin.xyz, 0.0, dir, 1.0 / 0.0);
    live_ids.data[i] = i;
    PathState s;
    s.throughput = vec4(1.0);
    s.radiance = vec4(0.0);
    s.depth = 0u;
    s.flags = PATH_DELTA;
    s.pad0 = 0u;
    s.pad1 = 0u;
    paths.data[i] = s;
}
