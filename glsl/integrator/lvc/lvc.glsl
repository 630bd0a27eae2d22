// Records and pure functions of the light-vertex-cache integrators (LVC-BDPT, CIS-LBDPT).
// src/integrator/lvc/gpu.rs is the Rust side (sizes asserted there, layouts checked by
// tests/suite/lvc_kernels.rs). The walks, techniques and MIS weights are those of the CPU BPT
// (src/bidir/: walk.rs, connect.rs, mis.rs, camera.rs), operation for operation where
// it matters, so that the CPU twins agree to rounding. Include geometry.glsl first.
#ifndef SPLITRAY_LVC_GLSL
#define SPLITRAY_LVC_GLSL

const float LVC_PI = 3.14159265358979323846;
const float LVC_INV_PI = 0.31830988618379067154;

// Settings of a whole render, in one read-only buffer at binding 0 of every kernel.
struct LvcConstants {
    vec3 origin;         // pinhole
    float pixel_area;    // a pixel's area on the image plane at distance 1
    vec3 forward;        // unit
    float ray_epsilon;   // offset of ray origins off surfaces
    vec3 right;          // scaled by the image plane's half width at distance 1
    float count_connection;   // n of the balance heuristic for s, t >= 2
    vec3 up;             // scaled by the half height
    float count_light_trace;  // n for t = 1 (the light paths of a pass)
    float count_emitter_hit;  // n for s = 0
    float count_light_sample; // n for s = 1, t >= 2
    uint width;
    uint height;
    uint seed;
    uint light_paths;    // N_L: light paths per pass
    int max_depth;       // Mitsuba's max_depth; < 0 unbounded
    uint rr_depth;       // Russian roulette from this vertex on
    uint light_count;    // entries of the light table
    uint flags;          // LVC_FLAG_*
    uint candidates;     // M: candidates per camera vertex (resampling)
    uint connections;    // N: connections per camera vertex
    float brightness_scale;  // the power of two splat-film values and the estimates
                             // squared into second moments are multiplied by
                             // (src/integrator/pt/lights.rs, brightness_scale)
    uint pad0;
    uint pad1;
    uint pad2;
};

const uint LVC_FLAG_SORTED = 1u;    // kernels read their items through the sorted order
const uint LVC_FLAG_SYSTEMATIC = 2u;  // camera_connect's resampled draws are systematic
const uint LVC_FLAG_NORMALS = 4u;     // the normals table has three per triangle (else a dummy)

// Per dispatch, as push constants (32 bytes).
struct LvcPush {
    uint first_pass;     // pass of the chunk's first item
    uint path_count;     // paths of the chunk
    uint active_count;   // live items this dispatch
    uint bounce;         // vertex index of the hits being shaded (1 = first hit)
    uint base;           // cache: first free slot; light tracing: first cache vertex
    uint capacity;       // cache: slots
    uint pixel_offset;   // camera pass: first pixel of the chunk
    uint pixel_count;    // camera pass: pixels of the chunk (path p: pixel
                         // pixel_offset + p % pixel_count, pass first_pass + p / pixel_count)
};

// 80 bytes: a surface vertex of a light subpath (the cache) or a camera subpath.
struct LvcVertex {
    vec3 p;
    uint material;
    vec3 ns;             // unit shading normal, on the geometric normal's side
    uint triangle;       // its geometric normal is normalize(e1 x e2) of this triangle
    vec3 wo;             // unit direction to the previous vertex
    float d_vcm;         // recursive MIS quantities on arrival (src/bidir/mis.rs)
    vec3 beta;           // throughput up to and including this vertex
    float d_vc;
    uint path;           // light path (in the chunk) or camera path
    uint depth;          // index in its subpath: 1 = the first hit
    uint flags;          // VERTEX_*
    uint ordinal;        // cache: index among its light path's cached vertices
};

const uint VERTEX_VALID = 1u;        // a surface was reached (camera records)
const uint VERTEX_CONNECTIBLE = 2u;  // its BSDF has a non-delta lobe
const uint VERTEX_EXTENDS = 4u;      // the walk may scatter from it (depth bound)

// 80 bytes: a subpath's random walk between two vertices (src/bidir/walk.rs `Walk`).
struct WalkState {
    vec3 beta;           // throughput
    float d_vcm;         // MIS quantities of the last vertex (before the pending update)
    vec3 carried;        // Russian roulette's measure: the scattering part of beta
    float d_vc;
    vec3 prev_p;         // the last vertex
    float pending_fwd;   // pending scatter: solid-angle density of the sampled direction
    vec3 prev_ng;        // its geometric normal (zero: the pinhole or a point light)
    float pending_rev;   // pending scatter: density of the reverse direction
    float pending_count; // pending scatter: the count of the last vertex's d_vcm term
    uint depth;          // index of the last vertex (0: the pinhole or the light)
    uint flags;          // WALK_*
    float eta2;          // product of eta^2 (camera walks)
};

const uint WALK_PENDING_EMISSION = 1u;  // d_vcm = direct, d_vc = emitted (emission densities)
const uint WALK_DELTA_POSITION = 2u;    // a point light
const uint WALK_PENDING_SCATTER = 4u;
const uint WALK_PENDING_DELTA = 8u;     // the pending scatter was a delta lobe

// 32 bytes: one technique's contribution waiting for its shadow ray.
struct Contribution {
    vec3 value;          // weighted (and scaled) contribution to the path's pixel
    uint code;           // technique: s | t << 16; CONTRIBUTION_NONE when there is none
    float weight;        // the balance-heuristic weight alone (tests, technique images)
    uint target;         // light tracing: splat slot pass * pixels + pixel; else the cache
                         // vertex of a connection (or ~0u)
    uint pad0;
    uint pad1;
};

const uint CONTRIBUTION_NONE = 0xFFFFFFFFu;

// The records by device address (address.glsl): kernels whose buffers grow with the
// scene or the film take every buffer so, and run their descriptor twins where the
// device reads descriptors faster and each buffer fits one binding.
#include "address.glsl"
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer LvcConstantsInRef { LvcConstants data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer LvcVerticesInRef { LvcVertex data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer LvcVerticesOutRef { LvcVertex data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer WalkStatesRef { WalkState data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer WalkStatesOutRef { WalkState data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer ContributionsInRef { Contribution data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer ContributionsOutRef { Contribution data[]; };

uint technique_code(uint s, uint t) { return s | (t << 16); }

// ---- random-number dimensions (src/bidir/random.rs `dims`) ------------------------

const uint DIMS_PER_VERTEX = 8u;
const uint DIM_CAMERA_JITTER = 0u;
const uint DIM_LIGHT_BASE = 1u << 30;
const uint DIM_BSDF = 0u;        // three
const uint DIM_ROULETTE = 3u;
const uint DIM_LIGHT_PICK = 4u;
const uint DIM_LIGHT_POINT = 5u; // two
const uint DIM_EMIT_PICK = 0u;
const uint DIM_EMIT_POINT = 1u;  // two
const uint DIM_EMIT_DIRECTION = 3u; // two
// Cache-vertex selection and resampling (src/integrator/lvc/gpu.rs `dims`): above every
// light dimension.
const uint DIM_SELECT_BASE = 0x80000000u;
const uint DIMS_PER_SELECTION = 64u;
const uint DIM_RESAMPLE = 32u;   // offsets >= this: the resampling draws

uint camera_dim(uint j, uint offset) { return 2u + j * DIMS_PER_VERTEX + offset; }
uint emission_dim(uint offset) { return DIM_LIGHT_BASE + offset; }
uint light_dim(uint i, uint offset) { return DIM_LIGHT_BASE + i * DIMS_PER_VERTEX + offset; }
uint select_dim(uint j, uint offset) { return DIM_SELECT_BASE + j * DIMS_PER_SELECTION + offset; }

// ---- technique counts (src/bidir/mis.rs `TechniqueCounts`) -------------------------

// The count of light-subpath vertex i's d_vcm term (TechniqueCounts::light_vertex).
float count_light_vertex(LvcConstants c, uint i) {
    return i == 1u ? c.count_light_sample : c.count_connection;
}

// The count of camera-subpath vertex j's d_vcm term (TechniqueCounts::camera_vertex);
// on an emitter, the term of a one-vertex light subpath: (1, 1) has count 0 here.
float count_camera_vertex(LvcConstants c, uint j, bool on_emitter) {
    if (j == 1u) return on_emitter ? 0.0 : c.count_light_trace;
    return on_emitter ? c.count_light_sample : c.count_connection;
}

// max_depth bounds a complete path's segments.
bool depth_allows(LvcConstants c, uint segments) {
    return c.max_depth < 0 || segments <= uint(c.max_depth);
}

// ---- recursive MIS (src/bidir/mis.rs `SubpathMis`) ---------------------------------

void mis_arrive(inout float d_vcm, inout float d_vc, float dist2, float cos_in) {
    d_vcm *= dist2 / cos_in;
    d_vc /= cos_in;
}

void mis_scatter(inout float d_vcm, inout float d_vc, float count_here, float cos_out,
                 float pdf_fwd, float pdf_rev, bool delta) {
    if (delta) {
        d_vc *= cos_out;
        d_vcm = 0.0;
    } else {
        d_vc = cos_out / pdf_fwd * (d_vc * pdf_rev + count_here * d_vcm);
        d_vcm = 1.0 / pdf_fwd;
    }
}

float mis_partial(LvcVertex v, float count_here, float pdf_rev) {
    return count_here * v.d_vcm + pdf_rev * v.d_vc;
}

float mis_balance(float others) { return 1.0 / (1.0 + others); }

// ---- the pinhole camera (src/bidir/camera.rs) -----------------------------------------

float camera_cos(LvcConstants c, vec3 dir) { return dot(dir, c.forward); }

float camera_pdf_direction(LvcConstants c, vec3 dir) {
    float k = camera_cos(c, dir);
    if (k <= 0.0) return 0.0;
    return 1.0 / (c.pixel_area * k * k * k);
}

float camera_importance(LvcConstants c, vec3 dir) {
    float k = camera_cos(c, dir);
    if (k <= 0.0) return 0.0;
    return 1.0 / (c.pixel_area * k * k * k * k);
}

// The direction through film point (px + jx, py + jy) (CameraFrame::direction).
vec3 camera_direction(LvcConstants c, float x, float y) {
    float sx = 2.0 * x / float(c.width) - 1.0;
    float sy = 1.0 - 2.0 * y / float(c.height);
    return normalize(c.forward + sx * c.right + sy * c.up);
}

// The pixel the unit direction passes through, or ~0u (PinholeCamera::pixel_of).
uint camera_pixel_of(LvcConstants c, vec3 dir) {
    float k = camera_cos(c, dir);
    if (k <= 0.0) return 0xFFFFFFFFu;
    vec3 on_plane = dir / k - c.forward;
    float sx = dot(on_plane, c.right) / dot(c.right, c.right);
    float sy = dot(on_plane, c.up) / dot(c.up, c.up);
    float x = (sx + 1.0) * 0.5 * float(c.width);
    float y = (1.0 - sy) * 0.5 * float(c.height);
    if (!(x >= 0.0 && x < float(c.width) && y >= 0.0 && y < float(c.height))) return 0xFFFFFFFFu;
    uint px = min(uint(x), c.width - 1u);
    uint py = min(uint(y), c.height - 1u);
    return py * c.width + px;
}

// ---- geometry helpers ------------------------------------------------------------------

// |cos| of a unit direction against a geometric normal; 1 where there is none.
float abs_cos(vec3 ng, vec3 w) { return ng == vec3(0.0) ? 1.0 : abs(dot(ng, w)); }

// p moved off its surface to the side dir points to (CpuScene::offset).
vec3 offset_ray_origin(vec3 p, vec3 ng, vec3 dir, float eps) {
    if (ng == vec3(0.0)) return p;
    return p + ng * (dot(ng, dir) > 0.0 ? eps : -eps);
}

// The shadow ray between a and b (CpuScene::unoccluded): an end on a surface (non-zero
// geometric normal) moves off it towards the other, and the ray stops 1e-4 of its length
// short. False (and a ray of tmax 0, which nothing hits) when the ends coincide.
bool shadow_ray(vec3 a, vec3 a_ng, vec3 b, vec3 b_ng, float eps, out Ray r) {
    vec3 d0 = b - a;
    vec3 from = offset_ray_origin(a, a_ng, d0, eps);
    vec3 to = offset_ray_origin(b, b_ng, -d0, eps);
    vec3 d = to - from;
    float reach = length(d);
    r = Ray(from, 0.0, vec3(0.0, 0.0, 1.0), 0.0);
    if (!(reach > 0.0)) return false;
    r = Ray(from, 0.0, d / reach, reach * (1.0 - 1e-4));
    return true;
}

// A ray that the tracers report as a miss without work.
Ray no_ray() { return Ray(vec3(0.0), 0.0, vec3(0.0, 0.0, 1.0), 0.0); }

float max3(vec3 v) { return max(v.r, max(v.g, v.b)); }

float lvc_luminance(vec3 c) { return dot(c, vec3(0.212671, 0.715160, 0.072169)); }

#endif
