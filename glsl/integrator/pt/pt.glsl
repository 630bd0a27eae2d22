// Shared records of the wavefront path tracer (src/integrator/pt/gpu.rs is the Rust
// side; sizes are asserted there).
#ifndef SPLITRAY_PT_GLSL
#define SPLITRAY_PT_GLSL

// Push constants of every pt kernel: 128 bytes.
struct PtParams {
    vec4 origin;         // xyz camera position
    vec4 forward;        // xyz unit forward
    vec4 right;          // xyz right, scaled by the half width of the image plane at 1
    vec4 up;             // xyz up, scaled by the half height
    uint width;
    uint height;
    uint sample_index;   // which sample of the pixel this pass takes
    uint seed;
    uint pixel_offset;   // first pixel of the chunk
    uint path_count;     // paths in the chunk: pixel_count x (samples in the chunk)
    uint active_count;   // live paths this bounce
    uint bounce;         // 0 for camera rays
    int max_depth;       // Mitsuba's max_depth; < 0 = unbounded
    uint rr_depth;       // Russian roulette from this depth on (Mitsuba's rr_depth)
    uint light_count;    // entries of the light table
    uint flags;          // PT_FLAG_*
    float ray_epsilon;   // offset of secondary-ray origins (Aabb::ray_epsilon)
    uint pixel_count;    // pixels in the chunk; path p takes pixel pixel_offset +
                         // p % pixel_count, sample sample_index + p / pixel_count
    float brightness_scale;  // finish squares radiance times this power of two
                             // (src/integrator/pt/lights.rs, brightness_scale)
    uint pad2;
};

const uint PT_FLAG_SORTED = 1u;  // shade reads its items through the sorted order
const uint PT_FLAG_NEE = 2u;     // next-event estimation on
const uint PT_FLAG_BSDF = 4u;    // emission found by BSDF sampling counts
const uint PT_FLAG_NORMALS = 8u; // the normals table has three per triangle (else a dummy)
// Both NEE and BSDF on = multiple importance sampling (power heuristic).

// 48 bytes per path.
struct PathState {
    vec4 throughput;     // rgb beta; a = product of eta^2 (Mitsuba's RR uses beta * eta^2)
    vec4 radiance;       // rgb radiance gathered so far this sample; a = previous BSDF pdf
    uint depth;          // path vertices so far (Mitsuba's depth)
    uint flags;          // PATH_DELTA: the previous scattering event was a delta lobe
    uint pad0;
    uint pad1;
};

const uint PATH_DELTA = 1u;

// The records by device address (address.glsl).
#include "address.glsl"
layout(buffer_reference, std430, buffer_reference_align = 16) buffer PathStatesRef { PathState data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer PathStatesInRef { PathState data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer PathStatesOutRef { PathState data[]; };

// 64 bytes per light. Triangles: p0/e1/e2 in world space, a = area in e1.w;
// points: p0 = position. emission: radiance (triangles) or intensity (points);
// emission.w = probability of choosing this light.
struct Light {
    vec4 p0_type;        // xyz; w = 0 triangle, 1 point
    vec4 e1_area;        // xyz edge 1; w area
    vec4 e2_tri;         // xyz edge 2; w = triangle index (as float bits)
    vec4 emission_pmf;
};

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer LightsInRef { Light data[]; };

const uint LIGHT_TRIANGLE = 0u;
const uint LIGHT_POINT = 1u;

// Per material: emission (rgb) and the BSDF's flags.
struct PtMaterial {
    vec4 emission;       // rgb emitted radiance (one-sided, front = geometric normal)
    uint key;            // material_key(type, id): the sort key
    uint all_delta;      // 1 when every layer is a delta lobe (no NEE)
    uint sort_rank;      // the key's rank among the scene's keys (what sort_keys sorts)
    uint pad0;
};

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer PtMaterialsInRef { PtMaterial data[]; };

// Random-number dimensions: 0, 1 for the pixel position, then DIMS_PER_BOUNCE per bounce.
const uint DIMS_PER_BOUNCE = 8u;
uint pt_dim(uint bounce, uint k) { return 2u + bounce * DIMS_PER_BOUNCE + k; }
const uint DIM_LIGHT_SELECT = 0u;
const uint DIM_LIGHT_U = 1u;
const uint DIM_LIGHT_V = 2u;
const uint DIM_BSDF_C = 3u;
const uint DIM_BSDF_U = 4u;
const uint DIM_BSDF_V = 5u;
const uint DIM_RR = 6u;

uint pt_pixel(PtParams q, uint p) { return q.pixel_offset + p % q.pixel_count; }
uint pt_sample(PtParams q, uint p) { return q.sample_index + p / q.pixel_count; }

float pt_luminance(vec3 c) { return dot(c, vec3(0.212671, 0.715160, 0.072169)); }

#endif
