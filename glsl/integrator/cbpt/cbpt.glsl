// CBPT's combination kernels (§4 of Pajot et al. 2011): the linking vertices and the
// push constants they share. The Rust side is src/integrator/cbpt/layout.rs and gpu.rs;
// tests/suite/cbpt_gpu.rs checks the layouts and every kernel against its CPU twin
// (src/integrator/cbpt/cpu_kernels.rs).
#ifndef SPLITRAY_CBPT_GLSL
#define SPLITRAY_CBPT_GLSL

#include "bsdf.glsl"

// 64 bytes (GpuVertex): a camera vertex past the pinhole, a light vertex on a surface,
// or the first vertex of a light path (on a light; ng zero for a point light).
struct CbptVertex {
    vec3 p;
    uint material;  // the BSDF (surfaces)
    vec3 ng;        // unit geometric normal
    float pad0;
    vec3 ns;        // unit shading normal
    float pad1;
    vec3 wo;        // unit direction towards the previous vertex of the subpath
    float pad2;
};

// 32 bytes (CbptPush). A batch is segments first .. first + count of its kind; the
// segment's row vertex is segment / inner, its column vertex segment % inner (inner =
// V_L for camera-vertex major kernels, V_C for light shading).
struct CbptPush {
    uint first;
    uint count;
    uint inner;
    uint plane;          // floats per result plane (the batch capacity)
    float ray_epsilon;   // offset of ray ends off surfaces
    float shadow_reach;  // the fraction of a shadow ray's length tested
    uint pad0;
    uint pad1;
};

// a · b summed left to right without contraction, as glam's Vec3::dot.
float cbpt_dot(vec3 a, vec3 b) {
    precise float d = a.x * b.x + a.y * b.y + a.z * b.z;
    return d;
}

// The BSDF of surface vertex v towards the unit direction dir: f |cos| (times the
// shading-normal correction for importance), the density towards dir and the reverse
// one (src/bidir/connect.rs `endpoint`).
void cbpt_endpoint(BsdfParams bsdf, CbptVertex v, vec3 dir, uint mode,
                   out vec3 f, out float pdf_fwd, out float pdf_rev) {
    mat3 frame = bsdf_frame(v.ns);
    vec3 wo = bsdf_to_local(frame, v.wo);
    vec3 wi = bsdf_to_local(frame, dir);
    f = bsdf_eval(bsdf, wo, wi, mode) * abs(wi.z);
    if (mode == TRANSPORT_IMPORTANCE) f *= bsdf_shading_correction(v.wo, dir, v.ns, v.ng, mode);
    pdf_fwd = bsdf_pdf(bsdf, wo, wi, mode);
    pdf_rev = bsdf_pdf(bsdf, wi, wo, mode);
}

#endif
