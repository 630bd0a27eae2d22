// A connection endpoint's BSDF (src/bidir/connect.rs `Endpoint`): needs the BsdfParams
// buffer `bsdfs` (a BUFFER_REF or BUFFER_BINDING of address.glsl).
#ifndef SPLITRAY_LVC_BSDF_GLSL
#define SPLITRAY_LVC_BSDF_GLSL

struct Endpoint {
    vec3 f;          // f |wi.ns| (importance: the adjoint, with the shading-normal correction)
    float pdf_fwd;   // density of sampling towards the other endpoint
    float pdf_rev;   // density of sampling towards this vertex's predecessor from there
};

// What an endpoint's evaluations share, whatever the other endpoint: loaded once when
// one vertex connects to several (camera_connect.comp).
struct EndpointBsdf {
    BsdfParams b;
    mat3 frame;
    vec3 wo;    // local
};

EndpointBsdf endpoint_bsdf(LvcVertex v) {
    EndpointBsdf e;
    BSDF_LOAD(e.b, bsdfs.data[v.material]);
    e.frame = bsdf_frame(v.ns);
    e.wo = bsdf_to_local(e.frame, v.wo);
    return e;
}

Endpoint endpoint_eval_with(EndpointBsdf s, LvcVertex v, vec3 ng, vec3 dir, uint mode) {
    vec3 wi = bsdf_to_local(s.frame, dir);
    Endpoint e;
    e.f = bsdf_eval(s.b, s.wo, wi, mode) * abs(wi.z);
    if (mode == TRANSPORT_IMPORTANCE) e.f *= bsdf_shading_correction(v.wo, dir, v.ns, ng, mode);
    e.pdf_fwd = bsdf_pdf(s.b, s.wo, wi, mode);
    e.pdf_rev = bsdf_pdf(s.b, wi, s.wo, mode);
    return e;
}

Endpoint endpoint_eval(LvcVertex v, vec3 ng, vec3 dir, uint mode) {
    return endpoint_eval_with(endpoint_bsdf(v), v, ng, dir, mode);
}

#endif
