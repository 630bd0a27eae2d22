#version 460
// Test kernel: the frame and shading-normal helpers of bsdf.glsl against
// src/bsdf/frame.rs and shading_normal_correction (tests/suite/bsdf_gpu.rs). Per query
// (wo, wi, ns, ng as vec4s) writes 4 vec4s: the frame's s and t for ns, wo in that
// frame, and (to_world(to_local(wo)), correction for radiance, for importance).
#include "grid.glsl"
#include "bsdf.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Queries { vec4 queries[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Results { vec4 results[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    vec3 wo = queries[4u * i].xyz;
    vec3 wi = queries[4u * i + 1u].xyz;
    vec3 ns = queries[4u * i + 2u].xyz;
    vec3 ng = queries[4u * i + 3u].xyz;
    mat3 f = bsdf_frame(ns);
    vec3 local = bsdf_to_local(f, wo);
    results[4u * i] = vec4(f[0], bsdf_shading_correction(wo, wi, ns, ng, TRANSPORT_RADIANCE));
    results[4u * i + 1u] = vec4(f[1], bsdf_shading_correction(wo, wi, ns, ng, TRANSPORT_IMPORTANCE));
    results[4u * i + 2u] = vec4(local, 0.0);
    results[4u * i + 3u] = vec4(bsdf_to_world(f, local), 0.0);
}
