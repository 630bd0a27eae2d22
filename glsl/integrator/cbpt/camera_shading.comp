#version 460
// CBPT camera shading: for every linking segment of the batch (camera-vertex major, so
// the threads of one camera vertex are consecutive and share its BSDF: Fig. 2) the
// camera vertex's BSDF towards the light vertex — f |cos|, p(x_{i-1} -> x_i -> y_j) and
// p*(y_j -> x_i -> x_{i-1}) — as five planes of floats (structure of arrays: coalesced
// writes). Zero where the two ends coincide.
#include "grid.glsl"
#include "cbpt.glsl"

layout(push_constant) uniform Push { CbptPush pc; };
layout(std430, set = 0, binding = 0) readonly buffer Camera { CbptVertex camera[]; };
layout(std430, set = 0, binding = 1) readonly buffer Light { CbptVertex light[]; };
layout(std430, set = 0, binding = 2) readonly buffer Bsdfs { BsdfParams bsdfs[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Results { float results[]; };

void main() {
    uint i = linear_invocation_id();
    if (i >= pc.count) return;
    uint segment = pc.first + i;
    uint c = segment / pc.inner;
    CbptVertex z = camera[c];
    CbptVertex y = light[segment - c * pc.inner];
    precise vec3 to = y.p - z.p;
    float dist2 = cbpt_dot(to, to);
    vec3 f = vec3(0.0);
    float pdf_fwd = 0.0;
    float pdf_rev = 0.0;
    if (dist2 > 0.0) {
        precise vec3 dir = to / sqrt(dist2);
        BsdfParams bsdf;
        BSDF_LOAD(bsdf, bsdfs[z.material]);
        cbpt_endpoint(bsdf, z, dir, TRANSPORT_RADIANCE, f, pdf_fwd, pdf_rev);
    }
    results[i] = f.r;
    results[pc.plane + i] = f.g;
    results[2u * pc.plane + i] = f.b;
    results[3u * pc.plane + i] = pdf_fwd;
    results[4u * pc.plane + i] = pdf_rev;
}
