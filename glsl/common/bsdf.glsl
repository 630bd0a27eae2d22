// BSDFs and layered materials in the local shading frame. The twin of src/bsdf/ (read
// its module docs for the conventions): +z = shading normal, wo and wi point away from
// the surface, ior = eta_inside / eta_outside (+z is outside), TransportMode as in
// pbrt-v4 (1/eta'^2 at refraction for radiance only). eval returns f (not f cos), pdf
// is per solid angle, delta lobes are reached only through bsdf_sample.
#ifndef SPLITRAY_BSDF_GLSL
#define SPLITRAY_BSDF_GLSL

#include "sampling.glsl"

const uint BSDF_MAX_LAYERS = 4u;

const uint BSDF_KIND_LAMBERT = 0u;
const uint BSDF_KIND_OREN_NAYAR = 1u;
const uint BSDF_KIND_MIRROR = 2u;
const uint BSDF_KIND_DIELECTRIC = 3u;
const uint BSDF_KIND_MICROFACET_REFLECTION = 4u;
const uint BSDF_KIND_MICROFACET_DIELECTRIC = 5u;

const uint DIST_BLINN_PHONG = 0u;
const uint DIST_BECKMANN = 1u;
const uint DIST_GGX = 2u;

const uint BSDF_REFLECTION = 1u;
const uint BSDF_TRANSMISSION = 2u;
const uint BSDF_DIFFUSE = 4u;
const uint BSDF_GLOSSY = 8u;
const uint BSDF_SPECULAR = 16u;

const uint TRANSPORT_RADIANCE = 0u;
const uint TRANSPORT_IMPORTANCE = 1u;

const float BSDF_PI = 3.14159265358979323846;

// 32 bytes (src/bsdf/mod.rs BsdfLayer).
struct BsdfLayer {
    vec4 tint_weight;   // rgb albedo / tint / Schlick F0; a = mixture weight
    uint kind;          // BSDF_KIND_*
    uint distribution;  // DIST_* (microfacet kinds)
    float roughness;    // Oren-Nayar sigma (rad); alpha (Beckmann, GGX); exponent (Blinn-Phong)
    float ior;          // eta_inside / eta_outside (dielectric kinds)
};

// 144 bytes (src/bsdf/mod.rs BsdfParams).
struct BsdfParams {
    BsdfLayer layers[BSDF_MAX_LAYERS];
    uint count;
    uint pad0;
    uint pad1;
    uint pad2;
};

#include "address.glsl"
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer BsdfsInRef { BsdfParams data[]; };

// DST = SRC (a stack in a buffer) with only SRC's first `count` layers loaded: the layers
// past it are never read (every loop over a stack stops at its count). A plain copy loads
// all BSDF_MAX_LAYERS, which cost lavapipe's connection kernels a fifth of their time
// (each load there is a gather across the SIMD lanes).
#define BSDF_LOAD(DST, SRC) \
    DST.count = SRC.count; \
    for (uint bsdf_k_ = 0u; bsdf_k_ < BSDF_MAX_LAYERS; ++bsdf_k_) { \
        if (bsdf_k_ < DST.count) DST.layers[bsdf_k_] = SRC.layers[bsdf_k_]; \
    }

struct BsdfSample {
    vec3 f;
    float pdf;
    vec3 wi;
    uint flags;
    float eta;
    uint layer;
    bool valid;
};

BsdfSample bsdf_no_sample() {
    BsdfSample s;
    s.f = vec3(0.0);
    s.pdf = 0.0;
    s.wi = vec3(0.0);
    s.flags = 0u;
    s.eta = 1.0;
    s.layer = 0u;
    s.valid = false;
    return s;
}

BsdfSample bsdf_make_sample(vec3 f, vec3 wi, float pdf, uint flags, float eta) {
    BsdfSample s;
    s.f = f;
    s.pdf = pdf;
    s.wi = wi;
    s.flags = flags;
    s.eta = eta;
    s.layer = 0u;
    s.valid = true;
    return s;
}

// ---- material keys (thesis 4.4.2; src/bsdf/key.rs) --------------------------------

uint material_key(uint type_, uint id) { return (type_ << 24) | (id & 0xFFFFFFu); }
uint material_key_type(uint key) { return key >> 24; }
uint material_key_id(uint key) { return key & 0xFFFFFFu; }

// ---- frames ----------------------------------------------------------------------

// Columns s, t, n with n = +z of the local frame (Duff et al. 2017); src/bsdf/frame.rs.
mat3 bsdf_frame(vec3 n) {
    float sgn = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + n.z);
    float b = n.x * n.y * a;
    vec3 s = vec3(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
    vec3 t = vec3(b, sgn + n.y * n.y * a, -n.y);
    return mat3(s, t, n);
}
vec3 bsdf_to_local(mat3 frame, vec3 v) { return vec3(dot(v, frame[0]), dot(v, frame[1]), dot(v, frame[2])); }
vec3 bsdf_to_world(mat3 frame, vec3 v) { return frame[0] * v.x + frame[1] * v.y + frame[2] * v.z; }

// Shading-normal correction of the adjoint BSDF: 1 for radiance, else
// |wo.ns||wi.ng| / (|wo.ng||wi.ns|) (world space); 0 when the denominator vanishes.
float bsdf_shading_correction(vec3 wo, vec3 wi, vec3 ns, vec3 ng, uint mode) {
    if (mode == TRANSPORT_RADIANCE) return 1.0;
    float num = abs(dot(wo, ns)) * abs(dot(wi, ng));
    float denom = abs(dot(wo, ng)) * abs(dot(wi, ns));
    return denom == 0.0 ? 0.0 : num / denom;
}

// ---- helpers ---------------------------------------------------------------------

bool same_hemisphere(vec3 wo, vec3 wi) { return wo.z * wi.z > 0.0; }

float fresnel_dielectric(float cos_i, float eta) {
    // No interface reflects nothing, exactly (src/bsdf/specular.rs).
    if (eta == 1.0) return 0.0;
    cos_i = clamp(cos_i, -1.0, 1.0);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    float sin2_i = 1.0 - cos_i * cos_i;
    float sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0) return 1.0;
    float cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    float r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return (r_parl * r_parl + r_perp * r_perp) * 0.5;
}

vec3 fresnel_schlick(vec3 f0, float c) {
    float m = clamp(1.0 - abs(c), 0.0, 1.0);
    float m2 = m * m;
    return f0 + (vec3(1.0) - f0) * (m2 * m2 * m);
}

vec3 bsdf_reflect(vec3 w, vec3 n) { return -w + n * (2.0 * dot(w, n)); }

// Refraction of w (pointing away) through normal n, eta = eta(-n side) / eta(n side).
// Returns false under total internal reflection; etap = eta_t / eta_i of the crossing.
bool bsdf_refract(vec3 w, vec3 n, float eta, out vec3 wt, out float etap) {
    // No interface bends nothing, exactly.
    if (eta == 1.0) {
        wt = -w;
        etap = 1.0;
        return true;
    }
    float cos_i = dot(w, n);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    float sin2_i = max(1.0 - cos_i * cos_i, 0.0);
    float sin2_t = sin2_i / (eta * eta);
    wt = vec3(0.0);
    etap = eta;
    if (sin2_t >= 1.0) return false;
    float cos_t = sqrt(1.0 - sin2_t);
    wt = -w / eta + n * (cos_i / eta - cos_t);
    return true;
}

// ---- Lambert and Oren-Nayar --------------------------------------------------------

vec3 lambert_eval(vec3 albedo, vec3 wo, vec3 wi) {
    if (!same_hemisphere(wo, wi)) return vec3(0.0);
    return albedo * (1.0 / BSDF_PI);
}

float lambert_pdf(vec3 wo, vec3 wi) {
    if (!same_hemisphere(wo, wi)) return 0.0;
    return cosine_hemisphere_pdf(wi.z);
}

bool lambert_sample_wi(vec3 wo, float u1, float u2, out vec3 wi) {
    wi = vec3(0.0);
    if (wo.z == 0.0) return false;
    wi = cosine_hemisphere(u1, u2);
    if (wo.z < 0.0) wi.z = -wi.z;
    return wi.z != 0.0;
}

vec3 oren_nayar_eval(vec3 albedo, float sigma, vec3 wo, vec3 wi) {
    if (!same_hemisphere(wo, wi)) return vec3(0.0);
    float s2 = sigma * sigma;
    float a = 1.0 - s2 / (2.0 * (s2 + 0.33));
    float b = 0.45 * s2 / (s2 + 0.09);
    float sin_i = sqrt(max(1.0 - wi.z * wi.z, 0.0));
    float sin_o = sqrt(max(1.0 - wo.z * wo.z, 0.0));
    float max_cos = 0.0;
    if (sin_i > 1e-4 && sin_o > 1e-4) {
        float cpi = clamp(wi.x / sin_i, -1.0, 1.0);
        float spi = clamp(wi.y / sin_i, -1.0, 1.0);
        float cpo = clamp(wo.x / sin_o, -1.0, 1.0);
        float spo = clamp(wo.y / sin_o, -1.0, 1.0);
        max_cos = max(cpi * cpo + spi * spo, 0.0);
    }
    float sin_alpha, tan_beta;
    if (abs(wi.z) > abs(wo.z)) {
        sin_alpha = sin_o;
        tan_beta = sin_i / abs(wi.z);
    } else {
        sin_alpha = sin_i;
        tan_beta = sin_o / abs(wo.z);
    }
    return albedo * ((1.0 / BSDF_PI) * (a + b * max_cos * sin_alpha * tan_beta));
}

// ---- microfacet distributions (src/bsdf/microfacet.rs) ------------------------------

// tan^2 as (x^2 + y^2) / z^2: no cancellation near the pole, invariant to normalization
// rounding (src/bsdf/microfacet.rs).
float mf_tan2_theta(vec3 w) {
    return (w.x * w.x + w.y * w.y) / (w.z * w.z);
}

// ln cos^2: ln(1 - sin^2) by its series near the pole, ln z^2 elsewhere.
float mf_ln_cos2_theta(vec3 w) {
    float s2 = w.x * w.x + w.y * w.y;
    if (s2 < 0.01) return -s2 * (1.0 + s2 * (0.5 + s2 * (1.0 / 3.0 + s2 * (0.25 + s2 * 0.2))));
    return log(max(w.z * w.z, 1e-30));
}

// Walter 2007's Blinn-Phong exponent -> Beckmann alpha.
float blinn_phong_alpha(float n) { return sqrt(2.0 / (n + 2.0)); }

float mf_d(uint dist, float a, vec3 m) {
    if (m.z <= 0.0) return 0.0;
    if (dist == DIST_BLINN_PHONG) return (a + 2.0) * (0.5 / BSDF_PI) * exp(0.5 * a * mf_ln_cos2_theta(m));
    float cos2 = m.z * m.z;
    float tan2 = mf_tan2_theta(m);
    if (isinf(tan2)) return 0.0;
    float a2 = a * a;
    if (dist == DIST_BECKMANN) return exp(-tan2 / a2) / (BSDF_PI * a2 * cos2 * cos2);
    float e = 1.0 + tan2 / a2;
    return 1.0 / (BSDF_PI * a2 * cos2 * cos2 * e * e);
}

// erfc(x), x >= 0, Abramowitz-Stegun 7.1.26.
float erfc_approx(float x) {
    float t = 1.0 / (1.0 + 0.3275911 * x);
    float poly = t * (0.2548296 + t * (-0.28449672 + t * (1.4214138 + t * (-1.453152 + t * 1.0614054))));
    return poly * exp(-x * x);
}

float mf_lambda(uint dist, float a, vec3 w) {
    float tan2 = mf_tan2_theta(w);
    if (isinf(tan2) || isnan(tan2)) return 0.0;
    if (dist == DIST_GGX) return (sqrt(1.0 + a * a * tan2) - 1.0) * 0.5;
    float alpha = dist == DIST_BECKMANN ? a : blinn_phong_alpha(a);
    float tan_t = sqrt(tan2);
    if (tan_t == 0.0) return 0.0;
    float x = 1.0 / (alpha * tan_t);
    float l = exp(-x * x) * (0.5 / sqrt(BSDF_PI)) / x - 0.5 * erfc_approx(x);
    return max(l, 0.0);
}

float mf_g1(uint dist, float a, vec3 w) { return 1.0 / (1.0 + mf_lambda(dist, a, w)); }

float mf_g(uint dist, float a, vec3 wo, vec3 wi) {
    return 1.0 / (1.0 + mf_lambda(dist, a, wo) + mf_lambda(dist, a, wi));
}

// m ~ D(m) cos(theta_m) on the +z hemisphere; sin^2 without cancellation.
vec3 mf_sample_m(uint dist, float a, float u1, float u2) {
    float sin_theta, cos_theta;
    if (dist == DIST_BLINN_PHONG) {
        float l = 2.0 * log(u1) / (a + 2.0);
        float sin2 = l > -0.01
            ? -l * (1.0 + l * (0.5 + l * (1.0 / 6.0 + l * (1.0 / 24.0 + l * (1.0 / 120.0)))))
            : 1.0 - exp(l);
        sin_theta = sqrt(max(sin2, 0.0));
        cos_theta = sqrt(max(1.0 - sin2, 0.0));
    } else {
        float tan2 = dist == DIST_BECKMANN ? -(a * a) * log(1.0 - u1) : a * a * u1 / (1.0 - u1);
        cos_theta = 1.0 / sqrt(1.0 + tan2);
        sin_theta = sqrt(tan2) * cos_theta;
    }
    float phi = 2.0 * BSDF_PI * u2;
    return vec3(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta);
}

float mf_pdf_m(uint dist, float a, vec3 m) { return mf_d(dist, a, m) * abs(m.z); }

// ---- microfacet reflection (Schlick F0 = tint), two-sided ---------------------------

vec3 mf_reflection_eval(vec3 f0, uint dist, float a, vec3 wo, vec3 wi) {
    if (!same_hemisphere(wo, wi)) return vec3(0.0);
    if (wo.z < 0.0) {
        wo.z = -wo.z;
        wi.z = -wi.z;
    }
    vec3 wm = wo + wi;
    if (dot(wm, wm) == 0.0) return vec3(0.0);
    wm = normalize(wm);
    vec3 f = fresnel_schlick(f0, dot(wi, wm));
    return f * (mf_d(dist, a, wm) * mf_g(dist, a, wo, wi) / (4.0 * wi.z * wo.z));
}

float mf_reflection_pdf(uint dist, float a, vec3 wo, vec3 wi) {
    if (!same_hemisphere(wo, wi)) return 0.0;
    if (wo.z < 0.0) {
        wo.z = -wo.z;
        wi.z = -wi.z;
    }
    vec3 wm = wo + wi;
    if (dot(wm, wm) == 0.0) return 0.0;
    wm = normalize(wm);
    return mf_pdf_m(dist, a, wm) / (4.0 * abs(dot(wo, wm)));
}

bool mf_reflection_sample_wi(uint dist, float a, vec3 wo, float u1, float u2, out vec3 wi) {
    wi = vec3(0.0);
    if (wo.z == 0.0) return false;
    vec3 flip = vec3(1.0, 1.0, wo.z < 0.0 ? -1.0 : 1.0);
    vec3 wo_up = wo * flip;
    vec3 m = mf_sample_m(dist, a, u1, u2);
    if (dot(wo_up, m) <= 0.0) return false;
    wi = bsdf_reflect(wo_up, m);
    if (wi.z <= 0.0) return false;
    wi *= flip;
    return true;
}

// ---- rough dielectric (Walter 2007 / pbrt-v4 DielectricBxDF) -------------------------

bool mf_dielectric_half(float eta, vec3 wo, vec3 wi, out vec3 wm, out float etap, out bool refl) {
    wm = vec3(0.0, 0.0, 1.0);
    etap = 1.0;
    refl = false;
    float cos_o = wo.z, cos_i = wi.z;
    if (cos_o == 0.0 || cos_i == 0.0) return false;
    refl = cos_i * cos_o > 0.0;
    if (!refl) etap = cos_o > 0.0 ? eta : 1.0 / eta;
    wm = wi * etap + wo;
    if (dot(wm, wm) == 0.0) return false;
    wm = normalize(wm);
    if (wm.z < 0.0) wm = -wm;
    if (dot(wm, wi) * cos_i <= 0.0 || dot(wm, wo) * cos_o <= 0.0) return false;
    return true;
}

// F at m for the pair, from the optically thinner side (see src/bsdf/microfacet.rs).
float mf_fresnel_pair(float eta, vec3 wo, vec3 wi, vec3 wm, float etap) {
    return etap < 1.0 ? fresnel_dielectric(dot(wi, wm), eta) : fresnel_dielectric(dot(wo, wm), eta);
}

vec3 mf_dielectric_eval(vec3 tint, uint dist, float a, float eta, vec3 wo, vec3 wi, uint mode) {
    // eta = 1: a delta lobe only (src/bsdf/microfacet.rs).
    if (eta == 1.0) return vec3(0.0);
    vec3 wm;
    float etap;
    bool refl;
    if (!mf_dielectric_half(eta, wo, wi, wm, etap, refl)) return vec3(0.0);
    float f = mf_fresnel_pair(eta, wo, wi, wm, etap);
    float dg = mf_d(dist, a, wm) * mf_g(dist, a, wo, wi);
    if (refl) return tint * (dg * f / abs(4.0 * wi.z * wo.z));
    float denom = dot(wi, wm) + dot(wo, wm) / etap;
    denom = denom * denom;
    float ft = dg * (1.0 - f) * abs(dot(wi, wm) * dot(wo, wm) / (wi.z * wo.z * denom));
    if (mode == TRANSPORT_RADIANCE) ft /= etap * etap;
    return tint * ft;
}

float mf_dielectric_pdf(uint dist, float a, float eta, vec3 wo, vec3 wi) {
    if (eta == 1.0) return 0.0;
    vec3 wm;
    float etap;
    bool refl;
    if (!mf_dielectric_half(eta, wo, wi, wm, etap, refl)) return 0.0;
    float r = mf_fresnel_pair(eta, wo, wi, wm, etap);
    float pm = mf_pdf_m(dist, a, wm);
    if (refl) return pm / (4.0 * abs(dot(wo, wm))) * r;
    float denom = dot(wi, wm) + dot(wo, wm) / etap;
    return pm * (abs(dot(wi, wm)) / (denom * denom)) * (1.0 - r);
}

bool mf_dielectric_sample_wi(uint dist, float a, float eta, vec3 wo, vec3 u, out vec3 wi,
                             out uint flags, out float etap) {
    wi = vec3(0.0);
    flags = 0u;
    etap = 1.0;
    if (wo.z == 0.0) return false;
    vec3 m = mf_sample_m(dist, a, u.y, u.z);
    float cos_om = dot(wo, m);
    if (cos_om * wo.z <= 0.0) return false;
    float r = fresnel_dielectric(cos_om, eta);
    if (u.x < r) {
        wi = bsdf_reflect(wo, m);
        flags = BSDF_REFLECTION | BSDF_GLOSSY;
        return wi.z * wo.z > 0.0;
    }
    if (!bsdf_refract(wo, m, eta, wi, etap)) return false;
    flags = BSDF_TRANSMISSION | BSDF_GLOSSY;
    return wi.z * wo.z < 0.0;
}

// ---- one layer ---------------------------------------------------------------------

// The layer kinds a pipeline can meet, bit k for BSDF_KIND k (specialization constant 2;
// every kind by default). A kind left out is compiled out: lavapipe's LLVM spends most
// of a kernel's first dispatch compiling the microfacet and dielectric code that a scene
// of diffuse walls never runs (src/bsdf/mod.rs `layer_kinds`).
layout(constant_id = 2) const uint BSDF_KINDS = 0xFFFFFFFFu;
#define BSDF_HAS(KIND) ((BSDF_KINDS & (1u << (KIND))) != 0u)

vec3 layer_eval(BsdfLayer l, vec3 wo, vec3 wi, uint mode) {
    vec3 rgb = l.tint_weight.rgb;
    if (BSDF_HAS(BSDF_KIND_LAMBERT) && l.kind == BSDF_KIND_LAMBERT) return lambert_eval(rgb, wo, wi);
    if (BSDF_HAS(BSDF_KIND_OREN_NAYAR) && l.kind == BSDF_KIND_OREN_NAYAR)
        return oren_nayar_eval(rgb, l.roughness, wo, wi);
    if (BSDF_HAS(BSDF_KIND_MICROFACET_REFLECTION) && l.kind == BSDF_KIND_MICROFACET_REFLECTION)
        return mf_reflection_eval(rgb, l.distribution, l.roughness, wo, wi);
    if (BSDF_HAS(BSDF_KIND_MICROFACET_DIELECTRIC) && l.kind == BSDF_KIND_MICROFACET_DIELECTRIC)
        return mf_dielectric_eval(rgb, l.distribution, l.roughness, l.ior, wo, wi, mode);
    return vec3(0.0);
}

float layer_pdf(BsdfLayer l, vec3 wo, vec3 wi) {
    if ((BSDF_HAS(BSDF_KIND_LAMBERT) && l.kind == BSDF_KIND_LAMBERT)
        || (BSDF_HAS(BSDF_KIND_OREN_NAYAR) && l.kind == BSDF_KIND_OREN_NAYAR))
        return lambert_pdf(wo, wi);
    if (BSDF_HAS(BSDF_KIND_MICROFACET_REFLECTION) && l.kind == BSDF_KIND_MICROFACET_REFLECTION)
        return mf_reflection_pdf(l.distribution, l.roughness, wo, wi);
    if (BSDF_HAS(BSDF_KIND_MICROFACET_DIELECTRIC) && l.kind == BSDF_KIND_MICROFACET_DIELECTRIC)
        return mf_dielectric_pdf(l.distribution, l.roughness, l.ior, wo, wi);
    return 0.0;
}

// The smooth dielectric (src/bsdf/specular.rs dielectric_sample): reflects with
// probability R = F(cos theta_o), else refracts; uc makes the choice.
BsdfSample dielectric_sample(vec3 tint, float eta, vec3 wo, float uc, uint mode) {
    if (wo.z == 0.0) return bsdf_no_sample();
    float r = fresnel_dielectric(wo.z, eta);
    float t = 1.0 - r;
    vec3 wi;
    if (uc < r) {
        wi = vec3(-wo.x, -wo.y, wo.z);
        return bsdf_make_sample(tint * (r / abs(wi.z)), wi, r, BSDF_REFLECTION | BSDF_SPECULAR, 1.0);
    }
    float etap;
    if (!bsdf_refract(wo, vec3(0.0, 0.0, 1.0), eta, wi, etap)) return bsdf_no_sample();
    if (wi.z == 0.0 || t <= 0.0) return bsdf_no_sample();
    float ft = t / abs(wi.z);
    if (mode == TRANSPORT_RADIANCE) ft /= etap * etap;
    return bsdf_make_sample(tint * ft, wi, t, BSDF_TRANSMISSION | BSDF_SPECULAR, etap);
}

// Samples the layer's direction. For delta kinds f and pdf are set; for the others only
// wi, flags and eta (the caller evaluates f and pdf, as src/bsdf/mod.rs Bsdf::sample).
BsdfSample layer_sample_direction(BsdfLayer l, vec3 wo, vec3 u, uint mode) {
    vec3 rgb = l.tint_weight.rgb;
    vec3 wi;
    if ((BSDF_HAS(BSDF_KIND_LAMBERT) && l.kind == BSDF_KIND_LAMBERT)
        || (BSDF_HAS(BSDF_KIND_OREN_NAYAR) && l.kind == BSDF_KIND_OREN_NAYAR)) {
        if (!lambert_sample_wi(wo, u.y, u.z, wi)) return bsdf_no_sample();
        return bsdf_make_sample(vec3(0.0), wi, 0.0, BSDF_REFLECTION | BSDF_DIFFUSE, 1.0);
    }
    if (BSDF_HAS(BSDF_KIND_MIRROR) && l.kind == BSDF_KIND_MIRROR) {
        if (wo.z == 0.0) return bsdf_no_sample();
        wi = vec3(-wo.x, -wo.y, wo.z);
        return bsdf_make_sample(rgb / abs(wi.z), wi, 1.0, BSDF_REFLECTION | BSDF_SPECULAR, 1.0);
    }
    if (BSDF_HAS(BSDF_KIND_DIELECTRIC) && l.kind == BSDF_KIND_DIELECTRIC)
        return dielectric_sample(rgb, l.ior, wo, u.x, mode);
    if (BSDF_HAS(BSDF_KIND_MICROFACET_REFLECTION) && l.kind == BSDF_KIND_MICROFACET_REFLECTION) {
        if (!mf_reflection_sample_wi(l.distribution, l.roughness, wo, u.y, u.z, wi)) return bsdf_no_sample();
        return bsdf_make_sample(vec3(0.0), wi, 0.0, BSDF_REFLECTION | BSDF_GLOSSY, 1.0);
    }
    if (BSDF_HAS(BSDF_KIND_MICROFACET_DIELECTRIC) && l.kind == BSDF_KIND_MICROFACET_DIELECTRIC) {
        // No interface: straight through, the smooth dielectric of eta 1.
        if (l.ior == 1.0) return dielectric_sample(rgb, l.ior, wo, u.x, mode);
        uint flags;
        float etap;
        if (!mf_dielectric_sample_wi(l.distribution, l.roughness, l.ior, wo, u, wi, flags, etap))
            return bsdf_no_sample();
        return bsdf_make_sample(vec3(0.0), wi, 0.0, flags, etap);
    }
    return bsdf_no_sample();
}

// ---- the layered stack (thesis 4.4.1; src/bsdf/layered.rs) -----------------------------
// f = sum_k w_k f_k; layer k sampled with p_k = w_k / sum w; pdf = sum_k p_k pdf_k.

float bsdf_total_weight(BsdfParams p) {
    float total = 0.0;
    for (uint k = 0u; k < min(p.count, BSDF_MAX_LAYERS); ++k) total += max(p.layers[k].tint_weight.a, 0.0);
    return total;
}

vec3 bsdf_eval(BsdfParams p, vec3 wo, vec3 wi, uint mode) {
    vec3 f = vec3(0.0);
    for (uint k = 0u; k < min(p.count, BSDF_MAX_LAYERS); ++k) {
        float w = max(p.layers[k].tint_weight.a, 0.0);
        if (w > 0.0) f += layer_eval(p.layers[k], wo, wi, mode) * w;
    }
    return f;
}

float bsdf_pdf(BsdfParams p, vec3 wo, vec3 wi, uint mode) {
    float total = bsdf_total_weight(p);
    if (total <= 0.0) return 0.0;
    float pdf = 0.0;
    for (uint k = 0u; k < min(p.count, BSDF_MAX_LAYERS); ++k) {
        float w = max(p.layers[k].tint_weight.a, 0.0);
        if (w > 0.0) pdf += layer_pdf(p.layers[k], wo, wi) * (w / total);
    }
    return pdf;
}

// u = (uc, u1, u2) in [0,1): uc picks the layer (then, remapped, reflect vs refract).
BsdfSample bsdf_sample(BsdfParams p, vec3 wo, vec3 u, uint mode) {
    float total = bsdf_total_weight(p);
    if (total <= 0.0) return bsdf_no_sample();
    uint n = min(p.count, BSDF_MAX_LAYERS);
    int last = -1;
    for (uint k = 0u; k < n; ++k) {
        if (max(p.layers[k].tint_weight.a, 0.0) > 0.0) last = int(k);
    }
    if (last < 0) return bsdf_no_sample();
    uint chosen = 0u;
    float pk = 0.0;
    float uc = 0.0;
    float cdf = 0.0;
    for (uint k = 0u; k < n; ++k) {
        float p_k = max(p.layers[k].tint_weight.a, 0.0) / total;
        if (p_k <= 0.0) continue;
        if (u.x < cdf + p_k || int(k) == last) {
            chosen = k;
            pk = p_k;
            uc = clamp((u.x - cdf) / p_k, 0.0, ONE_MINUS_EPSILON);
            break;
        }
        cdf += p_k;
    }
    BsdfLayer l = p.layers[chosen];
    BsdfSample s = layer_sample_direction(l, wo, vec3(uc, u.y, u.z), mode);
    if (!s.valid) return s;
    s.layer = chosen;
    if ((s.flags & BSDF_SPECULAR) != 0u) {
        s.f *= max(l.tint_weight.a, 0.0);
        s.pdf *= pk;
        return s;
    }
    s.f = bsdf_eval(p, wo, s.wi, mode);
    s.pdf = bsdf_pdf(p, wo, s.wi, mode);
    if (!(s.pdf > 0.0)) return bsdf_no_sample();
    return s;
}

#endif
