#version 460
// Display: the film, or one of its AOVs, as packed 8-bit pixels for a window (or a
// snapshot), scaled into the output's view rectangle by nearest neighbour (integer
// arithmetic) on a grey background.
//
// Colour matches the PNG writer (src/film/png_out.rs) value for value: the estimate
// (sum / weight), times the exposure, clamped to [0, 1], sRGB-encoded to 8 bits; NaN or
// infinite estimates are magenta. The sRGB encoding is not evaluated here: the host
// gives, for each 8-bit value k, the smallest linear value the PNG writer encodes as k
// or more, and the pixel takes the number of those at or below it (a binary search), so
// no pow() approximation can round differently from the PNG. `precise` keeps the
// compiler from fusing multiply-adds, which would round differently from the CPU twin
// (src/display/tonemap.rs). Only the division by the weight may differ from it: Vulkan
// allows 2.5 ULP there (NVIDIA's is not correctly rounded), so an estimate lying exactly
// on an 8-bit step may show one value lower or higher than the PNG's on such a device.
#include "grid.glsl"

struct ToneParams {
    uint film_width;
    uint film_height;
    uint out_width;
    uint out_height;
    // x, y, width, height of the film's rectangle in the output.
    uvec4 view;
    float exposure;
    uint mode;
    uint bgra;
    float depth_near;
    float depth_scale;
    uint pad0;
    uint pad1;
    uint pad2;
};

layout(push_constant) uniform Push { ToneParams params; };
layout(std430, set = 0, binding = 0) readonly buffer Film { vec4 film[]; };
layout(std430, set = 0, binding = 1) readonly buffer Depth { float depth[]; };
layout(std430, set = 0, binding = 2) readonly buffer TriangleId { uint triangle_id[]; };
layout(std430, set = 0, binding = 3) readonly buffer Normal { vec4 normal[]; };
layout(std430, set = 0, binding = 4) readonly buffer Thresholds { float srgb_threshold[256]; };
layout(std430, set = 0, binding = 5) writeonly buffer Pixels { uint pixels[]; };

const uint MODE_COLOUR = 0u;
const uint MODE_DEPTH = 1u;
const uint MODE_NORMAL = 2u;
const uint MODE_TRIANGLE = 3u;
const uint NO_TRIANGLE = 0xFFFFFFFFu;
const float FLT_MAX = 3.402823466e38;
const float FLT_MIN = 1.175494351e-38;
const uvec3 BACKGROUND = uvec3(24u);
const uvec3 NON_FINITE = uvec3(255u, 0u, 255u);

// The 8-bit sRGB value of linear x in [0, 1]: how many thresholds 1..255 are <= x.
uint encode_srgb8(float x) {
    uint k = 0u;
    for (uint step = 128u; step > 0u; step >>= 1u) {
        if (srgb_threshold[k + step] <= x) k += step;
    }
    return k;
}

// x in [0, 1] to 8 bits, rounded to nearest.
uint unorm8(float x) {
    precise float scaled = x * 255.0 + 0.5;
    return uint(scaled);
}

// Subnormal values become zero here, explicitly: Vulkan lets each device flush them or
// not, and this way every device (and the CPU twin) shows the same pixels.
vec4 flush(vec4 v) {
    return mix(v, vec4(0.0), lessThan(abs(v), vec4(FLT_MIN)));
}

uvec3 colour(uint p) {
    vec4 s = flush(film[p]);
    vec3 mean = s.w > 0.0 ? flush(vec4(s.xyz / s.w, 0.0)).xyz : vec3(0.0);
    if (any(isnan(mean)) || any(isinf(mean))) return NON_FINITE;
    precise vec3 x = mean * params.exposure;
    x = max(x, vec3(0.0));
    // A finite estimate that a large exposure overflowed saturates.
    x = mix(x, vec3(FLT_MAX), isinf(x));
    x = min(x, vec3(1.0));
    return uvec3(encode_srgb8(x.r), encode_srgb8(x.g), encode_srgb8(x.b));
}

// Near hits bright, far hits dim (25 at the farthest), misses black.
uvec3 depth_view(uint p) {
    float d = depth[p];
    if (isnan(d) || isinf(d)) return uvec3(0u);
    precise float v = 1.0 - (d - params.depth_near) * params.depth_scale;
    v = clamp(v, 0.0, 1.0);
    precise float scaled = v * 230.0 + 0.5;
    return uvec3(25u + uint(scaled));
}

// The normal's components mapped from [-1, 1] to [0, 255]; misses black.
uvec3 normal_view(uint p) {
    vec3 n = normal[p].xyz;
    if (n == vec3(0.0)) return uvec3(0u);
    precise vec3 half_n = n * 0.5 + 0.5;
    half_n = clamp(half_n, vec3(0.0), vec3(1.0));
    return uvec3(unorm8(half_n.x), unorm8(half_n.y), unorm8(half_n.z));
}

// A colour per triangle (a PCG hash of its index, each channel in 64..255); misses black.
uvec3 triangle_view(uint p) {
    uint id = triangle_id[p];
    if (id == NO_TRIANGLE) return uvec3(0u);
    uint state = id * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    uint h = (word >> 22u) ^ word;
    uvec3 bytes = uvec3(h & 255u, (h >> 8u) & 255u, (h >> 16u) & 255u);
    return uvec3(64u) + bytes * 3u / 4u;
}

void main() {
    uint i = linear_invocation_id();
    if (i >= params.out_width * params.out_height) return;
    uint x = i % params.out_width;
    uint y = i / params.out_width;
    uvec3 rgb = BACKGROUND;
    // Unsigned: a pixel left of or above the view wraps around and falls outside it.
    uint vx = x - params.view.x;
    uint vy = y - params.view.y;
    if (vx < params.view.z && vy < params.view.w) {
        uint fx = vx * params.film_width / params.view.z;
        uint fy = vy * params.film_height / params.view.w;
        uint p = fy * params.film_width + fx;
        if (params.mode == MODE_DEPTH) {
            rgb = depth_view(p);
        } else if (params.mode == MODE_NORMAL) {
            rgb = normal_view(p);
        } else if (params.mode == MODE_TRIANGLE) {
            rgb = triangle_view(p);
        } else {
            rgb = colour(p);
        }
    }
    uvec3 packed_order = params.bgra != 0u ? rgb.bgr : rgb.rgb;
    pixels[i] = packed_order.x | (packed_order.y << 8u) | (packed_order.z << 16u) | 0xFF000000u;
}
