// Light sampling with the light table's semantics (src/bidir/lights.rs `Lights`): needs
// the buffers `lights` (pt.glsl's Light records) and `light_cdf` (floats), each a
// BUFFER_REF or BUFFER_BINDING of address.glsl.
#ifndef SPLITRAY_LVC_LIGHTS_GLSL
#define SPLITRAY_LVC_LIGHTS_GLSL

struct LightPoint {
    vec3 p;
    float pdf_area;   // pmf / area (triangles), pmf (point lights)
    vec3 n;           // unit front normal; zero for a point light
    bool delta;       // a point light
    vec3 radiance;    // Le, or the intensity of a point light
    bool valid;
};

// The first light whose cumulative probability exceeds u (Lights::pick).
uint lvc_pick_light(float u, uint count) {
    uint lo = 0u;
    uint hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u < light_cdf.data[mid]) hi = mid; else lo = mid + 1u;
    }
    return lo;
}

// The point of light k for (u1, u2) (Lights::point).
LightPoint lvc_light_point(uint k, float u1, float u2) {
    Light l = lights.data[k];
    LightPoint q;
    q.radiance = l.emission_pmf.rgb;
    float pmf = l.emission_pmf.w;
    if (floatBitsToUint(l.p0_type.w) == LIGHT_POINT) {
        q.p = l.p0_type.xyz;
        q.n = vec3(0.0);
        q.pdf_area = pmf;
        q.delta = true;
        q.valid = pmf > 0.0;
        return q;
    }
    vec3 e1 = l.e1_area.xyz;
    vec3 e2 = l.e2_tri.xyz;
    float area = l.e1_area.w;
    float su = sqrt(u1);
    float b1 = 1.0 - su;
    float b2 = u2 * su;
    vec3 c = cross(e1, e2);
    q.n = dot(c, c) > 0.0 ? normalize(c) : vec3(0.0);
    q.p = l.p0_type.xyz + b1 * e1 + b2 * e2;
    q.pdf_area = pmf / area;
    q.delta = false;
    q.valid = pmf > 0.0 && area > 0.0 && q.n != vec3(0.0);
    return q;
}

LightPoint lvc_sample_light(vec3 u, uint count) {
    LightPoint q;
    q.valid = false;
    if (count == 0u) return q;
    return lvc_light_point(lvc_pick_light(u.x, count), u.y, u.z);
}

#endif
