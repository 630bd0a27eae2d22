#version 460
// Test kernel: bsdf_sample for (params index, wo, random numbers, mode) queries, to
// compare with the Rust twin and to draw GPU samples for chi-square tests
// (tests/suite/bsdf_gpu.rs).
#include "grid.glsl"
#include "bsdf.glsl"

struct SampleQuery {
    vec3 wo;
    uint params;
    vec3 u;
    uint mode;
};

// 48 bytes.
struct SampleResult {
    vec3 f;
    float pdf;
    vec3 wi;
    uint flags;
    float eta;
    uint layer;
    uint valid;
    uint pad;
};

layout(std430, set = 0, binding = 0) readonly buffer Params { BsdfParams params[]; };
layout(std430, set = 0, binding = 1) readonly buffer Queries { SampleQuery queries[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Results { SampleResult results[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    SampleQuery q = queries[i];
    BsdfSample s = bsdf_sample(params[q.params], q.wo, q.u, q.mode);
    SampleResult r;
    r.f = s.f;
    r.pdf = s.pdf;
    r.wi = s.wi;
    r.flags = s.flags;
    r.eta = s.eta;
    r.layer = s.layer;
    r.valid = s.valid ? 1u : 0u;
    r.pad = 0u;
    results[i] = r;
}
