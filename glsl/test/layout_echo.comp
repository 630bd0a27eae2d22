#version 460
// Writes every field of the shared structs as floats, in declaration order, so
// tests/suite/trace_brute_force.rs can prove the Rust and GLSL layouts agree.
#include "grid.glsl"
#include "geometry.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 1) readonly buffer Hits { Hit hits[]; };
layout(std430, set = 0, binding = 2) readonly buffer Triangles { Triangle triangles[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Out { float fields[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    uint o = i * 24;
    Ray r = rays[i];
    fields[o + 0] = r.origin.x; fields[o + 1] = r.origin.y; fields[o + 2] = r.origin.z;
    fields[o + 3] = r.tmin;
    fields[o + 4] = r.dir.x; fields[o + 5] = r.dir.y; fields[o + 6] = r.dir.z;
    fields[o + 7] = r.tmax;
    Hit h = hits[i];
    fields[o + 8] = h.t; fields[o + 9] = float(h.triangle); fields[o + 10] = h.u; fields[o + 11] = h.v;
    Triangle t = triangles[i];
    fields[o + 12] = t.v0.x; fields[o + 13] = t.v0.y; fields[o + 14] = t.v0.z; fields[o + 15] = t.v0.w;
    fields[o + 16] = t.v1.x; fields[o + 17] = t.v1.y; fields[o + 18] = t.v1.z; fields[o + 19] = t.v1.w;
    fields[o + 20] = t.v2.x; fields[o + 21] = t.v2.y; fields[o + 22] = t.v2.z; fields[o + 23] = t.v2.w;
}
