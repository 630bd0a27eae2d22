#version 460
// CBPT light shading: for every linking segment of the batch whose light vertex lies on
// a surface (light-vertex major: segment = l · V_C + c, the threads of one light vertex
// consecutive) the light vertex's adjoint BSDF towards the camera vertex — f |cos| with
// the shading-normal correction, p*(y_{j-1} -> y_j -> x_i) and p(x_i -> y_j -> y_{j-1})
// — as five planes of floats. The direction is taken from the camera end, as a
// connection takes it. Zero where the two ends coincide.
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
    uint l = segment / pc.inner;
    CbptVertex y = light[l];
    CbptVertex z = camera[segment - l * pc.inner];
    precise vec3 to = y.p - z.p;
    float dist2 = cbpt_dot(to, to);
    vec3 f = vec3(0.0);
    float pdf_fwd = 0.0;
    float pdf_rev = 0.0;
    if (dist2 > 0.0) {
        precise vec3 dir = to / sqrt(dist2);
        BsdfParams bsdf;
        BSDF_LOAD(bsdf, bsdfs[y.material]);
        cbpt_endpoint(bsdf, y, -dir, TRANSPORT_IMPORTANCE, f, pdf_fwd, pdf_rev);
    }
    results[i] = f.r;
    results[pc.plane + i] = f.g;
    results[2u * pc.plane + i] = f.b;
    results[3u * pc.plane + i] = pdf_fwd;
    results[4u * pc.plane + i] = pdf_rev;
}
