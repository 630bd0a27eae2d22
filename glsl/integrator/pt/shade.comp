#version 460
// Stage `shade`: one invocation per live path (through the material-sorted order when
// sorting is on). At the hit it
//   1. adds emitted radiance, MIS-weighted against light sampling (power heuristic),
//   2. samples a light (next-event estimation): writes a shadow ray and the
//      unoccluded contribution, MIS-weighted against BSDF sampling,
//   3. samples the BSDF for the next ray, and
//   4. plays Russian roulette,
// following Mitsuba 3's `path` integrator step by step, so max_depth and rr_depth mean
// what they mean there (depth = path vertices after the camera; max_depth 1 = emitters
// seen directly, 2 = direct lighting, < 0 = unbounded).
//
// Every output is indexed by the path's position i in the (unsorted) active list and
// every random number is a function of (pixel, sample, dimension, seed): the order in
// which invocations run changes nothing, so sorting never changes the image.
#include "grid.glsl"
#include "geometry.glsl"
#include "random.glsl"
#include "bsdf.glsl"
#include "pt.glsl"

layout(push_constant) uniform Push {
    PtParams params;
    BUFFER_REF(RaysRef, rays)
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(UintsInRef, live_ids)
    BUFFER_REF(UintsInRef, order)
    BUFFER_REF(PathStatesRef, paths)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(UintsInRef, triangle_material)
    BUFFER_REF(PtMaterialsInRef, materials)
    BUFFER_REF(BsdfsInRef, bsdfs)
    BUFFER_REF(Vec4sInRef, normals)
    BUFFER_REF(LightsInRef, lights)
    BUFFER_REF(FloatsInRef, light_cdf)
    BUFFER_REF(FloatsInRef, tri_light_pmf)
    BUFFER_REF(RaysOutRef, shadow_rays)
    BUFFER_REF(Vec4sOutRef, nee)
    BUFFER_REF(UintsOutRef, alive)
};
BUFFER_BINDING(0, , Ray, rays)
BUFFER_BINDING(1, readonly, Hit, hits)
BUFFER_BINDING(2, readonly, uint, live_ids)
BUFFER_BINDING(3, readonly, uint, order)
BUFFER_BINDING(4, , PathState, paths)
BUFFER_BINDING(5, readonly, Triangle, triangles)
BUFFER_BINDING(6, readonly, uint, triangle_material)
BUFFER_BINDING(7, readonly, PtMaterial, materials)
BUFFER_BINDING(8, readonly, BsdfParams, bsdfs)
BUFFER_BINDING(9, readonly, vec4, normals)
BUFFER_BINDING(10, readonly, Light, lights)
BUFFER_BINDING(11, readonly, float, light_cdf)
BUFFER_BINDING(12, readonly, float, tri_light_pmf)
BUFFER_BINDING(13, writeonly, Ray, shadow_rays)
BUFFER_BINDING(14, writeonly, vec4, nee)
BUFFER_BINDING(15, writeonly, uint, alive)

float power_heuristic(float a, float b) {
    float a2 = a * a;
    float b2 = b * b;
    return a2 + b2 > 0.0 ? a2 / (a2 + b2) : 0.0;
}

// First light whose cumulative probability exceeds u.
uint pick_light(float u) {
    uint lo = 0u;
    uint hi = params.light_count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u < light_cdf.data[mid]) hi = mid; else lo = mid + 1u;
    }
    return lo;
}

void main() {
    uint j = linear_invocation_id();
    if (j >= params.active_count) return;
    uint i = (params.flags & PT_FLAG_SORTED) != 0u ? order.data[j] : j;
    uint p = live_ids.data[i];
    uint pixel = pt_pixel(params, p);
    uint sample_index = pt_sample(params, p);
    PathState s = paths.data[p];
    Ray ray = rays.data[i];
    Hit hit = hits.data[i];

    shadow_rays.data[i] = Ray(ray.origin, 0.0, ray.dir, 0.0);
    nee.data[i] = vec4(0.0);
    alive.data[i] = 0u;
    if (hit.triangle == MISS) return;  // no environment light

    Triangle tri = triangles.data[hit.triangle];
    uint mat = triangle_material.data[hit.triangle];
    PtMaterial m = materials.data[mat];
    vec3 cross_n = triangle_normal(tri);
    vec3 ng = normalize(cross_n);
    vec3 x = ray.origin + hit.t * ray.dir;
    vec3 beta = s.throughput.rgb;
    vec3 radiance = s.radiance.rgb;
    float prev_pdf = s.radiance.a;
    bool prev_delta = (s.flags & PATH_DELTA) != 0u;
    bool mis = (params.flags & (PT_FLAG_NEE | PT_FLAG_BSDF)) == (PT_FLAG_NEE | PT_FLAG_BSDF);

    // 1. Emission (one-sided: front = geometric normal). max_depth 0 sees nothing, not
    // even emitters (Mitsuba's meaning).
    float cos_l = -dot(ng, ray.dir);
    if (params.max_depth != 0 && m.emission.r + m.emission.g + m.emission.b > 0.0 && cos_l > 0.0) {
        float w = 1.0;
        if (!prev_delta) {
            if ((params.flags & PT_FLAG_BSDF) == 0u) {
                w = 0.0;  // NEE-only: emitters count only through light sampling
            } else if (mis) {
                float area = 0.5 * length(cross_n);
                float pdf_light = tri_light_pmf.data[hit.triangle] * hit.t * hit.t / (area * cos_l);
                w = power_heuristic(prev_pdf, pdf_light);
            }
        }
        radiance += beta * m.emission.rgb * w;
    }

    bool next = (params.max_depth < 0 || int(s.depth) + 1 < params.max_depth);
    if (!next) {
        paths.data[p].radiance.rgb = radiance;
        return;
    }

    // Shading frame: interpolated normals where the mesh has them, else geometric.
    vec3 ns = ng;
    bool has_normals = (params.flags & PT_FLAG_NORMALS) != 0u;
    vec4 n0 = has_normals ? normals.data[3u * hit.triangle] : vec4(0.0);
    if (n0.w != 0.0) {
        vec3 n1 = normals.data[3u * hit.triangle + 1u].xyz;
        vec3 n2 = normals.data[3u * hit.triangle + 2u].xyz;
        vec3 n = (1.0 - hit.u - hit.v) * n0.xyz + hit.u * n1 + hit.v * n2;
        if (dot(n, n) > 0.0) {
            ns = normalize(n);
            if (dot(ns, ng) < 0.0) ns = -ns;
        }
    }
    mat3 frame = bsdf_frame(ns);
    BsdfParams bsdf;
    BSDF_LOAD(bsdf, bsdfs.data[mat]);
    vec3 wo = bsdf_to_local(frame, -ray.dir);
    float eps = params.ray_epsilon;

    // 2. Next-event estimation.
    if ((params.flags & PT_FLAG_NEE) != 0u && params.light_count > 0u && m.all_delta == 0u) {
        uint d0 = pt_dim(params.bounce, DIM_LIGHT_SELECT);
        uint li = pick_light(random01(pixel, sample_index, d0, params.seed));
        Light light = lights.data[li];
        float u1 = random01(pixel, sample_index, pt_dim(params.bounce, DIM_LIGHT_U), params.seed);
        float u2 = random01(pixel, sample_index, pt_dim(params.bounce, DIM_LIGHT_V), params.seed);
        float pmf = light.emission_pmf.w;
        vec3 target;
        vec3 le = vec3(0.0);
        float pdf_light = 0.0;   // solid angle (area lights) or discrete (points)
        bool delta_light = floatBitsToUint(light.p0_type.w) == LIGHT_POINT;
        vec3 to = vec3(0.0);
        float dist = 0.0;
        if (delta_light) {
            target = light.p0_type.xyz;
            to = target - x;
            dist = length(to);
            if (dist > 0.0) {
                le = light.emission_pmf.rgb / (dist * dist);
                pdf_light = pmf;
            }
        } else {
            float su = sqrt(u1);
            float b1 = 1.0 - su;
            float b2 = u2 * su;
            target = light.p0_type.xyz + b1 * light.e1_area.xyz + b2 * light.e2_tri.xyz;
            to = target - x;
            dist = length(to);
            vec3 nl = normalize(cross(light.e1_area.xyz, light.e2_tri.xyz));
            float cl = dist > 0.0 ? -dot(nl, to) / dist : 0.0;
            if (cl > 0.0) {
                le = light.emission_pmf.rgb;
                pdf_light = pmf * dist * dist / (light.e1_area.w * cl);
            }
        }
        if (pdf_light > 0.0) {
            vec3 wi_world = to / dist;
            vec3 wi = bsdf_to_local(frame, wi_world);
            vec3 f = bsdf_eval(bsdf, wo, wi, TRANSPORT_RADIANCE) * abs(wi.z);
            if (f.r + f.g + f.b > 0.0) {
                float w = 1.0;
                if (!delta_light && mis) {
                    w = power_heuristic(pdf_light, bsdf_pdf(bsdf, wo, wi, TRANSPORT_RADIANCE));
                }
                vec3 c = beta * f * le * (w / pdf_light);
                vec3 o = x + ng * (dot(ng, wi_world) > 0.0 ? eps : -eps);
                float reach = length(target - o);
                shadow_rays.data[i] = Ray(o, 0.0, (target - o) / reach, reach * (1.0 - 1e-4));
                nee.data[i] = vec4(c, 1.0);
            }
        }
    }

    // 3. BSDF sampling.
    vec3 u = vec3(random01(pixel, sample_index, pt_dim(params.bounce, DIM_BSDF_C), params.seed),
                  random01(pixel, sample_index, pt_dim(params.bounce, DIM_BSDF_U), params.seed),
                  random01(pixel, sample_index, pt_dim(params.bounce, DIM_BSDF_V), params.seed));
    BsdfSample bs = bsdf_sample(bsdf, wo, u, TRANSPORT_RADIANCE);
    uint depth = s.depth + 1u;
    if (!bs.valid || !(bs.pdf > 0.0)) {
        paths.data[p].radiance.rgb = radiance;
        return;
    }
    beta *= bs.f * (abs(bs.wi.z) / bs.pdf);
    float eta2 = s.throughput.a * bs.eta * bs.eta;
    vec3 wi_world = normalize(bsdf_to_world(frame, bs.wi));

    // 4. Russian roulette (Mitsuba: from depth >= rr_depth, q = min(max(beta) eta^2, 0.95)).
    float beta_max = max(beta.r, max(beta.g, beta.b));
    bool live = beta_max > 0.0;
    if (live && depth >= params.rr_depth) {
        float q = min(beta_max * eta2, 0.95);
        float ur = random01(pixel, sample_index, pt_dim(params.bounce, DIM_RR), params.seed);
        if (ur < q) beta /= q; else live = false;
    }

    PathState o;
    o.throughput = vec4(beta, eta2);
    o.radiance = vec4(radiance, bs.pdf);
    o.depth = depth;
    o.flags = (bs.flags & BSDF_SPECULAR) != 0u ? PATH_DELTA : 0u;
    o.pad0 = 0u;
    o.pad1 = 0u;
    paths.data[p] = o;
    if (live) {
        vec3 origin = x + ng * (dot(ng, wi_world) > 0.0 ? eps : -eps);
        rays.data[i] = Ray(origin, 0.0, wi_world, 1.0 / 0.0);
        alive.data[i] = 1u;
    }
}
