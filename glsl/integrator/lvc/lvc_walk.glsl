// The random walks of both subpaths (src/bidir/walk.rs `Walk::extend` / `scatter`),
// one vertex per call. Needs the constants `C` and the buffer `triangles`; a kernel
// defines LVC_WALK_ARRIVE for walk_arrive (which needs the buffers `normals` with
// LVC_SHADING_NORMALS, `triangle_material` and `materials`) and LVC_WALK_SCATTER for
// walk_scatter (which needs `bsdfs`). Buffers are BUFFER_REFs or BUFFER_BINDINGs
// (address.glsl), read as `name.data[i]`.
#ifndef SPLITRAY_LVC_WALK_GLSL
#define SPLITRAY_LVC_WALK_GLSL

#ifdef LVC_WALK_ARRIVE
// The walk in state `s` traced `ray` to `hit`: the vertex it reaches, with its MIS
// quantities on arrival (the pending emission or scatter update first, with the cosine
// at the previous vertex taken between the two vertices' positions, as every connection
// takes it). False when the walk ends there (the points coincide or the ray grazes).
bool walk_arrive(inout WalkState s, Ray ray, Hit hit, uint path, out LvcVertex v) {
    vec3 x = ray.origin + hit.t * ray.dir;
    vec3 ng = triangle_normal(hit.triangle);
    vec3 to_prev = s.prev_p - x;
    float dist2 = dot(to_prev, to_prev);
    v.flags = 0u;
    if (!(dist2 > 0.0)) return false;
    vec3 wo = to_prev / sqrt(dist2);
    float cos_in = abs_cos(ng, wo);
    float cos_out = abs_cos(s.prev_ng, -wo);
    if (!(cos_in > 0.0)) return false;
    if ((s.flags & WALK_PENDING_EMISSION) != 0u) {
        // SubpathMis::light: d_vcm held the direct density, d_vc the emission density.
        float emitted = s.d_vc;
        s.d_vcm = s.d_vcm / emitted;
        s.d_vc = (s.flags & WALK_DELTA_POSITION) != 0u ? 0.0 : C.count_emitter_hit * cos_out / emitted;
    }
    if ((s.flags & WALK_PENDING_SCATTER) != 0u) {
        mis_scatter(s.d_vcm, s.d_vc, s.pending_count, cos_out, s.pending_fwd, s.pending_rev,
                    (s.flags & WALK_PENDING_DELTA) != 0u);
    }
    mis_arrive(s.d_vcm, s.d_vc, dist2, cos_in);
    uint material = triangle_material.data[hit.triangle];
    v.p = x;
    v.material = material;
    v.ns = shading_normal(hit, ng);
    v.triangle = hit.triangle;
    v.wo = wo;
    v.d_vcm = s.d_vcm;
    v.beta = s.beta;
    v.d_vc = s.d_vc;
    v.path = path;
    v.depth = s.depth + 1u;
    v.ordinal = 0u;
    v.flags = VERTEX_VALID;
    if (materials.data[material].all_delta == 0u) v.flags |= VERTEX_CONNECTIBLE;
    s.depth = v.depth;
    s.prev_p = x;
    s.prev_ng = ng;
    s.flags &= ~(WALK_PENDING_EMISSION | WALK_PENDING_SCATTER | WALK_PENDING_DELTA);
    return true;
}
#endif

#ifdef LVC_WALK_SCATTER
// Samples the direction out of vertex v (`ng` its geometric normal), plays Russian
// roulette and leaves the MIS update pending until the next vertex. `index`/`sample_index`
// are the subpath's random-number index (pixel or light path) and pass. False when the
// walk ends; else `next` is the ray to trace.
bool walk_scatter(inout WalkState s, LvcVertex v, vec3 ng, uint index, uint sample_index,
                  uint mode, out Ray next) {
    next = no_ray();
    BsdfParams b;
    BSDF_LOAD(b, bsdfs.data[v.material]);
    mat3 frame = bsdf_frame(v.ns);
    vec3 wo = bsdf_to_local(frame, v.wo);
    uint i = v.depth;
    bool radiance = mode == TRANSPORT_RADIANCE;
    uint d = radiance ? camera_dim(i, DIM_BSDF) : light_dim(i, DIM_BSDF);
    vec3 u = vec3(random01(index, sample_index, d, C.seed),
                  random01(index, sample_index, d + 1u, C.seed),
                  random01(index, sample_index, d + 2u, C.seed));
    BsdfSample bs = bsdf_sample(b, wo, u, mode);
    if (!bs.valid || !(bs.pdf > 0.0)) return false;
    vec3 wi = normalize(bsdf_to_world(frame, bs.wi));
    vec3 factor = bs.f * (abs(bs.wi.z) / bs.pdf);
    if (radiance) {
        s.eta2 *= bs.eta * bs.eta;
    } else {
        factor *= bsdf_shading_correction(v.wo, wi, v.ns, ng, mode);
    }
    s.carried *= factor;
    vec3 beta = v.beta * factor;
    if (!(max3(beta) > 0.0)) return false;
    if (i >= C.rr_depth) {
        float q = min(max3(s.carried) * s.eta2, 0.95);
        uint dr = radiance ? camera_dim(i, DIM_ROULETTE) : light_dim(i, DIM_ROULETTE);
        if (random01(index, sample_index, dr, C.seed) >= q) return false;
        beta /= q;
        s.carried /= q;
    }
    bool delta = (bs.flags & BSDF_SPECULAR) != 0u;
    // Delta lobes sample the same discrete probability both ways (src/bidir/mis.rs).
    float pdf_rev = delta ? bs.pdf : bsdf_pdf(b, bs.wi, wo, mode);
    s.beta = beta;
    s.pending_count = radiance ? count_camera_vertex(C, i, false) : count_light_vertex(C, i);
    s.pending_fwd = bs.pdf;
    s.pending_rev = pdf_rev;
    s.flags |= WALK_PENDING_SCATTER | (delta ? WALK_PENDING_DELTA : 0u);
    next = Ray(offset_ray_origin(v.p, ng, wi, C.ray_epsilon), 0.0, wi, 1.0 / 0.0);
    return true;
}
#endif

#endif
