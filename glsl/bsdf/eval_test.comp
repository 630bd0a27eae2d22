#version 460
// Test kernel: f and pdf of a BSDF stack for (params index, wo, wi, mode) queries, to
// compare with the Rust twin (tests/suite/bsdf_gpu.rs).
#include "grid.glsl"
#include "bsdf.glsl"

struct EvalQuery {
    vec3 wo;
    uint params;
    vec3 wi;
    uint mode;
};

layout(std430, set = 0, binding = 0) readonly buffer Params { BsdfParams params[]; };
layout(std430, set = 0, binding = 1) readonly buffer Queries { EvalQuery queries[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Results { vec4 results[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    EvalQuery q = queries[i];
    BsdfParams p = params[q.params];
    results[i] = vec4(bsdf_eval(p, q.wo, q.wi, q.mode), bsdf_pdf(p, q.wo, q.wi, q.mode));
}
