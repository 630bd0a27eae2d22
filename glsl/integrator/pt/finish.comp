#version 460
// Stage `finish`: each path's radiance becomes one sample of its pixel: the film sum
// gets L (w counts samples) and the second-moment sum gets (s L)^2 (for standard
// errors), s = params.brightness_scale, a power of two that puts the brightest emitter
// near 1: squared as it is, radiance above about 1e19 would overflow f32 and radiance
// below about 1e-22 vanish. The host divides s^2 back out exactly (FilmSums::from_gpu).
// One invocation per pixel adds the chunk's samples of that pixel in sample order, so
// the sums do not depend on scheduling. A non-finite sample would poison its pixel for
// good: it is dropped (it counts as a sample of zero, as in pbrt-v4) and
// counted in counters[0], which the render reports as `non_finite_dropped`. Both films
// hold each sum in two floats (film_sum.glsl): one per pixel of the film, then their
// remainders.
#include "grid.glsl"
#include "pt.glsl"
#include "film_sum.glsl"

layout(push_constant) uniform Push {
    PtParams params;
    BUFFER_REF(PathStatesInRef, paths)
    BUFFER_REF(Vec4sRef, accum)
    BUFFER_REF(Vec4sRef, accum2)
    BUFFER_REF(UintsRef, counters)
};
BUFFER_BINDING(0, readonly, PathState, paths)
BUFFER_BINDING(1, , vec4, accum)
BUFFER_BINDING(2, , vec4, accum2)
BUFFER_BINDING(3, , uint, counters)

void main() {
    uint i = linear_invocation_id();
    if (i >= params.pixel_count) return;
    uint pixel = params.pixel_offset + i;
    uint rest = pixel + params.width * params.height;
    vec4 sum = accum.data[pixel];
    vec4 sum_rest = accum.data[rest];
    vec4 sum2 = accum2.data[pixel];
    vec4 sum2_rest = accum2.data[rest];
    for (uint p = i; p < params.path_count; p += params.pixel_count) {
        vec3 l = paths.data[p].radiance.rgb;
        if (any(isnan(l)) || any(isinf(l))) {
            l = vec3(0.0);
            atomicAdd(counters.data[0], 1u);
        }
        precise vec3 scaled = l * params.brightness_scale;
        precise vec3 squared = scaled * scaled;
        film_add(sum, sum_rest, vec4(l, 1.0));
        film_add(sum2, sum2_rest, vec4(squared, 0.0));
    }
    accum.data[pixel] = sum;
    accum.data[rest] = sum_rest;
    accum2.data[pixel] = sum2;
    accum2.data[rest] = sum2_rest;
}
