#version 460
// A chunk's pass estimates into the film: per pixel of the chunk and pass, its camera
// path's radiance plus the light-tracing splats that landed on it in that pass (already
// divided by the pass's light paths); the film sum gets the estimate (w counts samples),
// the second-moment sum its square (for standard errors). The square is of the estimate
// times the brightness scale, a power of two that puts the brightest emitter near 1:
// squared as it is, an estimate above about 1e19 would overflow f32 and one below about
// 1e-22 vanish. The host divides the scale back out exactly (FilmSums::from_gpu). One
// invocation per pixel adds the passes in order, so the sums do not depend on
// scheduling. Both films hold each sum in two floats (film_sum.glsl): one per pixel of
// the film, then their remainders.
#include "grid.glsl"
#include "geometry.glsl"
#include "lvc.glsl"
#include "film_sum.glsl"

layout(push_constant) uniform Push {
    LvcPush P;
    BUFFER_REF(LvcConstantsInRef, constants)
    BUFFER_REF(Vec4sInRef, radiance)
    BUFFER_REF(UintsInRef, fixed_film)
    BUFFER_REF(Vec4sRef, accum)
    BUFFER_REF(Vec4sRef, accum2)
};
BUFFER_BINDING(0, readonly, LvcConstants, constants)
BUFFER_BINDING(1, readonly, vec4, radiance)
BUFFER_BINDING(2, readonly, uint, fixed_film)
BUFFER_BINDING(3, , vec4, accum)
BUFFER_BINDING(4, , vec4, accum2)
#define C constants.data[0]

#include "lvc_fixed.glsl"

void main() {
    uint i = linear_invocation_id();
    if (i >= P.pixel_count) return;
    uint pixel = P.pixel_offset + i;
    uint pixels = C.width * C.height;
    uint passes = P.path_count / P.pixel_count;
    uint rest = pixel + pixels;
    vec4 sum = accum.data[pixel];
    vec4 sum_rest = accum.data[rest];
    vec4 sum2 = accum2.data[pixel];
    vec4 sum2_rest = accum2.data[rest];
    for (uint q = 0u; q < passes; ++q) {
        vec3 splats = fixed_value(q * pixels + pixel) * (1.0 / C.brightness_scale);
        vec3 l = radiance.data[q * P.pixel_count + i].rgb + splats;
        precise vec3 scaled = l * C.brightness_scale;
        precise vec3 squared = scaled * scaled;
        film_add(sum, sum_rest, vec4(l, 1.0));
        film_add(sum2, sum2_rest, vec4(squared, 0.0));
    }
    accum.data[pixel] = sum;
    accum.data[rest] = sum_rest;
    accum2.data[pixel] = sum2;
    accum2.data[rest] = sum2_rest;
}
