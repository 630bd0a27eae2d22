// A connection endpoint's BSDF (src/bidir/connect.rs `Endpoint`): needs
// `BsdfParams bsdfs[]`.
#ifndef SPLITRAY_LVC_BSDF_GLSL
#define SPLITRAY_LVC_BSDF_GLSL

struct Endpoint {
    vec3 f;          // f |wi.ns| (importance: the adjoint, with the shading-normal correction)
    float pdf_fwd;   // density of sampling towards the other endpoint
    float pdf_rev;   // density of sampling towards this vertex's predecessor from there
};

Endpoint endpoint_eval(LvcVertex v, vec3 ng, vec3 dir, uint mode) {
    BsdfParams b = bsdfs[v.material];
    mat3 frame = bsdf_frame(v.ns);
    vec3 wo = bsdf_to_local(frame, v.wo);
    vec3 wi = bsdf_to_local(frame, dir);
    Endpoint e;
    e.f = bsdf_eval(b, wo, wi, mode) * abs(wi.z);
    if (mode == TRANSPORT_IMPORTANCE) e.f *= bsdf_shading_correction(v.wo, dir, v.ns, ng, mode);
    e.pdf_fwd = bsdf_pdf(b, wo, wi, mode);
    e.pdf_rev = bsdf_pdf(b, wi, wo, mode);
    return e;
}

#endif
