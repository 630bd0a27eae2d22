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

// 48 bytes: the three vertices (w unused). Vertices, not edges: a vertex that two
// triangles share is then the same bits in both, which the watertight test needs.
struct Triangle {
    vec4 v0;
    vec4 v1;
    vec4 v2;
};

// The unnormalised geometric normal (v1 - v0) x (v2 - v0); its side follows the winding.
vec3 triangle_normal(Triangle t) { return cross(t.v1.xyz - t.v0.xyz, t.v2.xyz - t.v0.xyz); }

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

// Whether no component is infinite or NaN, by the exponent bits: a compiler may assume
// that floats are neither (SPIR-V without SignedZeroInfNanPreserve) and fold isinf and
// isnan away, but not integer tests.
bool finite(vec3 v) {
    return all(lessThan(floatBitsToUint(v) & 0x7F800000u, uvec3(0x7F800000u)));
}

// `a` with the axis kz last, the other two in cyclic order (kz = 0: yzx, 1: zxy, 2: xyz):
// a rotation of the axes, so the sign of every edge function below keeps its meaning.
vec3 permute_to_z(vec3 a, uint kz) { return kz == 0u ? a.yzx : (kz == 1u ? a.zxy : a); }

// Watertight ray–triangle intersection (Woop, Benthin and Wald 2013, "Watertight
// Ray/Triangle Intersection"; pbrt-v4's IntersectTriangle without its double fallback).
// The vertices are moved into a frame where the ray starts at the origin and runs along
// +z (a translation, a rotation of the axes and a shear), and the three 2D edge
// functions decide. An edge two triangles share gives both exactly opposite edge
// functions (same vertex bits, same arithmetic, products that commute), and a zero
// counts as inside for both: a ray through a shared edge or vertex hits at least one of
// the triangles and never slips between them, which Möller–Trumbore's per-triangle
// rounding lets happen. `precise` keeps the compiler from fusing multiplies into adds
// here, which would break that antisymmetry.
//
// The ray's part (the axis permutation and the shear, with a division) is computed once
// per ray by `shear_ray`; `intersect_sheared` is the per-triangle part. Mirrored
// operation for operation by `ShearedRay` in src/trace/cpu.rs, so the CPU twin agrees
// to rounding (the division is the only operation Vulkan does not round correctly).

// A ray ready for the watertight test: its origin, the axis that becomes z (3 for a ray
// that meets nothing: an infinite or NaN origin or direction, or a zero direction, which
// would otherwise make the shear 0 and hit at t = 0) and the shear (sx, sy, sz).
struct ShearedRay {
    vec3 origin;
    uint kz;
    vec3 shear;
};

ShearedRay shear_ray(vec3 o, vec3 d) {
    vec3 ad = abs(d);
    uint kz = ad.x > ad.y ? (ad.x > ad.z ? 0u : 2u) : (ad.y > ad.z ? 1u : 2u);
    vec3 dp = permute_to_z(d, kz);
    if (!(finite(o) && finite(d)) || dp.z == 0.0) return ShearedRay(o, 3u, vec3(0.0));
    precise float sz = 1.0 / dp.z;
    precise float sx = -dp.x * sz;
    precise float sy = -dp.y * sz;
    return ShearedRay(o, kz, vec3(sx, sy, sz));
}

// Returns t in (tmin, tmax) or +inf, with the barycentrics (u, v) of p1 and p2. A ray in
// the triangle's plane (det == 0) and a degenerate triangle never hit.
float intersect_sheared(ShearedRay r, float tmin, float tmax, vec3 p0, vec3 p1, vec3 p2,
                        out float u, out float v) {
    u = 0.0;
    v = 0.0;
    if (r.kz > 2u) return 1.0 / 0.0;
    vec3 a = permute_to_z(p0 - r.origin, r.kz);
    vec3 b = permute_to_z(p1 - r.origin, r.kz);
    vec3 c = permute_to_z(p2 - r.origin, r.kz);
    precise float ax = a.x + r.shear.x * a.z, ay = a.y + r.shear.y * a.z;
    precise float bx = b.x + r.shear.x * b.z, by = b.y + r.shear.y * b.z;
    precise float cx = c.x + r.shear.x * c.z, cy = c.y + r.shear.y * c.z;
    precise float e0 = bx * cy - by * cx;
    precise float e1 = cx * ay - cy * ax;
    precise float e2 = ax * by - ay * bx;
    if ((e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0)) return 1.0 / 0.0;
    precise float det = e0 + e1 + e2;
    if (det == 0.0) return 1.0 / 0.0;
    precise float sz = r.shear.z;
    precise float scaled_t = (e0 * (sz * a.z) + e1 * (sz * b.z)) + e2 * (sz * c.z);
    precise float inv_det = 1.0 / det;
    precise float t = scaled_t * inv_det;
    if (!(t > tmin && t < tmax)) return 1.0 / 0.0;
    u = e1 * inv_det;
    v = e2 * inv_det;
    return t;
}

// The test for one ray and one triangle.
float intersect_triangle(vec3 o, vec3 d, float tmin, float tmax, vec3 p0, vec3 p1, vec3 p2,
                         out float u, out float v) {
    return intersect_sheared(shear_ray(o, d), tmin, tmax, p0, p1, p2, u, v);
}

#endif
