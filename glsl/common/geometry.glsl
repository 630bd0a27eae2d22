// Ray, hit and triangle layouts shared with Rust (src/trace/types.rs, checked by
// tests/suite/trace_brute_force.rs), and the one ray–triangle test every GPU tracer uses.
#ifndef SPLITRAY_GEOMETRY_GLSL
#define SPLITRAY_GEOMETRY_GLSL

// 32 bytes: the vec3 + float pairs pack into 16-byte slots under std430.
struct Ray {
    vec3 origin;
    float tmin;
    vec3 dir;
    float tmax;
};

// Whether the segment (tmin, tmax) holds no point: tmax <= tmin, or either is NaN (the
// integrators' "no ray"). Such a ray hits nothing. Rust twin: `Ray::is_empty`.
bool ray_is_empty(Ray r) { return !(r.tmax > r.tmin); }

// 16 bytes. triangle == MISS for no hit (t is then +inf).
struct Hit {
    float t;
    uint triangle;
    float u;
    float v;
};

// 48 bytes: vertex 0 and the two edges from it, precomputed on the host.
struct Triangle {
    vec4 v0;
    vec4 e1;
    vec4 e2;
};

const uint MISS = 0xFFFFFFFFu;

// The records by device address (address.glsl): scenes and ray batches outgrow one
// storage binding.
#include "address.glsl"
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer TrianglesInRef { Triangle data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer RaysInRef { Ray data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer RaysRef { Ray data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer RaysOutRef { Ray data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer HitsInRef { Hit data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer HitsRef { Hit data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer HitsOutRef { Hit data[]; };

// Möller–Trumbore. Returns t in (tmin, tmax) or +inf, with barycentrics (u, v).
// Mirrored operation for operation by `intersect_triangle` in src/trace/cpu.rs, so the
// CPU twin agrees to rounding. Edge-on and degenerate triangles (det == 0) never hit.
float intersect_triangle(vec3 o, vec3 d, float tmin, float tmax, vec3 v0, vec3 e1, vec3 e2,
                         out float u, out float v) {
    vec3 p = cross(d, e2);
    float det = dot(e1, p);
    u = 0.0;
    v = 0.0;
    if (det == 0.0) return 1.0 / 0.0;
    float inv_det = 1.0 / det;
    vec3 s = o - v0;
    u = dot(s, p) * inv_det;
    // Written as the Rust twin's `!(0.0..=1.0).contains(&u)` so that a NaN u misses too:
    // a ray with an infinite direction component makes det infinite, inv_det 0, u NaN
    // and t 0, a hit at t = 0 wherever tmin < 0 if NaN slipped through.
    if (!(u >= 0.0 && u <= 1.0)) return 1.0 / 0.0;
    vec3 q = cross(s, e1);
    v = dot(d, q) * inv_det;
    if (v < 0.0 || u + v > 1.0) return 1.0 / 0.0;
    float t = dot(e2, q) * inv_det;
    return (t > tmin && t < tmax) ? t : 1.0 / 0.0;
}

#endif
