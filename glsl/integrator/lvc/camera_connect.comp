#version 460
//! variant resampled: LVC_RESAMPLE
// Camera pass, stream 1 (Algorithm 8, line 7): connections (s >= 2, t >= 2) of the camera
// vertex to vertices of its pass's light vertex cache, written to slots i N + k (k < N)
// of the connections' shadow rays and contributions (bound from slot P.base of the
// buffers that direct lighting's slots start). Two variants: uniform (the default
// build) and resampled (LVC_RESAMPLE).
//
// Uniform (LVC-BDPT, Davidovic et al. 2014): N vertices drawn uniformly with replacement
// from the |C_q| vertices of pass q's N_L light paths. Each estimates
// (1/N_L) sum over the cache of the connection's contribution, so it is scaled by
// |C_q| / (N N_L).
//
// Resampled (CIS-LBDPT, thesis 4.4.3, as Talbot et al. 2005's resampled importance
// sampling): M candidates drawn uniformly (density q = 1 / |C_q|), each one's unoccluded
// contribution g (both BSDFs, the geometry term, the MIS weight) evaluated, its
// luminance taken as the target p^; then N of them drawn with replacement in proportion
// to p^, each weighted by (1 / p^(y)) (1 / M) sum_m p^(y_m) / q(y_m), so that
// g(y) V(y) (sum_m p^_m / p^(y)) |C_q| / (M N N_L) is unbiased wherever p^ > 0 when g > 0
// (luminance of a non-negative RGB value with positive weights). Only those N are traced,
// a candidate drawn more than once with one shadow ray. Keeping the best N instead would
// be biased. The N draws are systematic (the default; one u, draw k at (u + k) / N) or
// independent (--resampling independent): either way a candidate's expected count is
// N p^ / sum p^, so the expectation is the same. With M = N = 1 the sum over p^ is p^(y)
// itself, the weight exactly 1 and the result the uniform one (bit for bit where the
// compiler fuses the two variants' arithmetic alike: lavapipe does, NVIDIA's not always).
//
// The MIS weight is the path's alone, as if the selection were uniform (count
// C.count_connection = N N_L / E|C_q|), so the weights of a path's techniques sum to 1.
#extension GL_EXT_control_flow_attributes : require
#include "grid.glsl"
#include "geometry.glsl"
#include "random.glsl"
#include "bsdf.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push {
    LvcPush P;
    BUFFER_REF(LvcConstantsInRef, constants)
    BUFFER_REF(UintsInRef, live_ids)
    BUFFER_REF(UintsInRef, order)
    BUFFER_REF(LvcVerticesInRef, vertices)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(BsdfsInRef, bsdfs)
    BUFFER_REF(LvcVerticesInRef, cache)
    BUFFER_REF(UintsInRef, cache_index)
    BUFFER_REF(UintsInRef, path_offset)
    BUFFER_REF(RaysOutRef, shadow_rays)
    BUFFER_REF(ContributionsOutRef, contrib)
};
BUFFER_BINDING(0, readonly, LvcConstants, constants)
BUFFER_BINDING(1, readonly, uint, live_ids)
BUFFER_BINDING(2, readonly, uint, order)
BUFFER_BINDING(3, readonly, LvcVertex, vertices)
BUFFER_BINDING(4, readonly, Triangle, triangles)
BUFFER_BINDING(5, readonly, BsdfParams, bsdfs)
BUFFER_BINDING(6, readonly, LvcVertex, cache)
BUFFER_BINDING(7, readonly, uint, cache_index)
BUFFER_BINDING(8, readonly, uint, path_offset)
BUFFER_BINDING(9, writeonly, Ray, shadow_rays)
BUFFER_BINDING(10, writeonly, Contribution, contrib)
#define C constants.data[0]

#include "lvc_surface.glsl"
#include "lvc_bsdf.glsl"
#include "lvc_random.glsl"

#ifdef LVC_RESAMPLE
// Candidates (M) per camera vertex the pipeline holds: the run's M, at most 16
// (MAX_CANDIDATES in src/integrator/lvc/options.rs), set when the pipeline is made
// (src/integrator/lvc/kernels.rs). Sized to the run's M rather than to 16 because the
// shared memory of an invocation (24 bytes a candidate) bounds how many invocations a
// GPU keeps resident to hide the candidates' random reads of the cache.
layout(constant_id = 1) const uint CANDIDATE_CAPACITY = 16u;
shared uint candidate_slot[WORKGROUP_SIZE * CANDIDATE_CAPACITY];
shared vec4 candidate_value[WORKGROUP_SIZE * CANDIDATE_CAPACITY];   // g, MIS weight
shared float candidate_target[WORKGROUP_SIZE * CANDIDATE_CAPACITY];
#endif

// The unoccluded, MIS-weighted contribution of connecting camera vertex z (index j) to
// cache vertex y (src/bidir/connect.rs `Connector::connect`); zero when the path would
// be too long or nothing is carried.
vec3 connection(LvcVertex z, vec3 z_ng, EndpointBsdf zb, LvcVertex y, out float weight) {
    weight = 0.0;
    uint i = y.depth;
    uint j = z.depth;
    if ((y.flags & VERTEX_CONNECTIBLE) == 0u || !depth_allows(C, i + j + 1u)) return vec3(0.0);
    vec3 y_ng = triangle_normal(y.triangle);
    vec3 to = y.p - z.p;
    float dist2 = dot(to, to);
    if (!(dist2 > 0.0)) return vec3(0.0);
    vec3 dir = to / sqrt(dist2);
    // Both endpoints through one copy of the BSDF code: a loop that stays a loop halves
    // the kernel, whose compilation took most of the integrator's on lavapipe.
    Endpoint ez, ey;
    [[dont_unroll]] for (uint side = 0u; side < 2u; ++side) {
        bool light = side == 1u;
        EndpointBsdf b = light ? endpoint_bsdf(y) : zb;
        Endpoint e = endpoint_eval_with(b, light ? y : z, light ? y_ng : z_ng,
                                        light ? -dir : dir,
                                        light ? TRANSPORT_IMPORTANCE : TRANSPORT_RADIANCE);
        if (light) ey = e; else ez = e;
        // Nothing scatters towards y (y behind an opaque camera vertex, mostly): the
        // light vertex's material need not be loaded.
        if (!light && ez.f == vec3(0.0)) return vec3(0.0);
    }
    vec3 value = y.beta * ey.f * ez.f * z.beta / dist2;
    if (value == vec3(0.0)) return vec3(0.0);
    float light_rev = ez.pdf_fwd * abs_cos(y_ng, dir) / dist2;
    float light_partial = mis_partial(y, count_light_vertex(C, i), ey.pdf_rev);
    float camera_fwd = ey.pdf_fwd * abs_cos(z_ng, dir) / dist2;
    float camera_partial = mis_partial(z, count_camera_vertex(C, j, false), ez.pdf_rev);
    weight = mis_balance((light_rev * light_partial + camera_fwd * camera_partial)
                         / C.count_connection);
    return value * weight;
}

// Slot `slot` gets the connection to cache vertex `k` of contribution g (times `scale`).
void emit(uint slot, LvcVertex z, vec3 z_ng, uint k, vec3 g, float weight, float scale) {
    LvcVertex y = cache.data[k];
    Ray r;
    if (g == vec3(0.0) || !shadow_ray(z.p, z_ng, y.p, triangle_normal(y.triangle),
                                      C.ray_epsilon, r)) return;
    shadow_rays.data[slot] = r;
    contrib.data[slot] = Contribution(g * scale, technique_code(y.depth + 1u, z.depth + 1u), weight,
                                      k, 0u, 0u);
}

void main() {
    uint jj = linear_invocation_id();
    if (jj >= P.active_count) return;
    uint i = (C.flags & LVC_FLAG_SORTED) != 0u ? order.data[jj] : jj;
    uint n = C.connections;
    uint first = i * n;
    for (uint k = 0u; k < n; ++k) {
        shadow_rays.data[first + k] = no_ray();
        contrib.data[first + k] = Contribution(vec3(0.0), CONTRIBUTION_NONE, 0.0, CONTRIBUTION_NONE,
                                               0u, 0u);
    }
    LvcVertex z = vertices.data[i];
    uint need = VERTEX_VALID | VERTEX_CONNECTIBLE;
    if ((z.flags & need) != need || !(C.count_connection > 0.0)) return;
    uint c = live_ids.data[i];
    uint pixel = P.pixel_offset + c % P.pixel_count;
    uint pass_in_chunk = c / P.pixel_count;
    uint pass = P.first_pass + pass_in_chunk;
    uint start = path_offset.data[pass_in_chunk * C.light_paths];
    uint size = path_offset.data[(pass_in_chunk + 1u) * C.light_paths] - start;
    if (size == 0u) return;
    uint j = z.depth;
    vec3 z_ng = triangle_normal(z.triangle);
    EndpointBsdf zb = endpoint_bsdf(z);
    uint threshold = uniform_threshold(size);

#ifndef LVC_RESAMPLE
    float scale = float(size) / (float(n) * float(C.light_paths));
    for (uint k = 0u; k < n; ++k) {
        uint pick = uniform_index_below(pixel, pass, select_dim(j, k), C.seed, size, threshold);
        uint slot = cache_index.data[start + pick];
        float weight;
        vec3 g = connection(z, z_ng, zb, cache.data[slot], weight);
        emit(first + k, z, z_ng, slot, g, weight, scale);
    }
#else
    // The candidates live in shared memory, each invocation its own CANDIDATE_CAPACITY
    // entries (function-local arrays indexed in loops blow up some drivers' compilers).
    uint m_count = min(C.candidates, CANDIDATE_CAPACITY);
    uint own = gl_LocalInvocationIndex * CANDIDATE_CAPACITY;
    float total = 0.0;
    for (uint m = 0u; m < m_count; ++m) {
        uint pick = uniform_index_below(pixel, pass, select_dim(j, m), C.seed, size, threshold);
        uint slot = cache_index.data[start + pick];
        float weight;
        vec3 g = connection(z, z_ng, zb, cache.data[slot], weight);
        float target = max(lvc_luminance(g), 0.0);
        candidate_slot[own + m] = slot;
        candidate_value[own + m] = vec4(g, weight);
        candidate_target[own + m] = target;
        total += target;
    }
    if (!(total > 0.0)) return;
    float scale = float(size) / (float(m_count) * float(n) * float(C.light_paths));
    // The N draws' candidates, four bits each (m < CANDIDATE_CAPACITY <= 16, k < 16).
    uvec2 picks = uvec2(0u);
    bool systematic = (C.flags & LVC_FLAG_SYSTEMATIC) != 0u;
    // Systematic draws share one uniform number: draw k sits at (u + k) / N
    // (src/integrator/lvc/options.rs `Resampling`).
    float shared_u = random01(pixel, pass, select_dim(j, DIM_RESAMPLE), C.seed);
    for (uint k = 0u; k < n; ++k) {
        // The first candidate whose running sum exceeds u * total (the last one with a
        // non-zero target when rounding leaves u * total at the very end).
        float u01 = systematic ? (shared_u + float(k)) / float(n)
                               : random01(pixel, pass, select_dim(j, DIM_RESAMPLE + k), C.seed);
        float u = u01 * total;
        uint chosen = 0u;
        float running = 0.0;
        for (uint m = 0u; m < m_count; ++m) {
            float target = candidate_target[own + m];
            if (target > 0.0) {
                chosen = m;
                running += target;
                if (u < running) break;
            }
        }
        picks[k >> 3] |= chosen << ((k & 7u) * 4u);
    }
    // A candidate drawn c times is one shadow ray (its visibility is the same each time)
    // in the slot of its first draw, its contribution counted c times; the slots of the
    // repeated draws stay empty. The estimate is the same sum, with fewer rays to trace.
    for (uint k = 0u; k < n; ++k) {
        uint chosen = (picks[k >> 3] >> ((k & 7u) * 4u)) & 0xFu;
        uint earlier = 0u;
        uint copies = 0u;
        for (uint l = 0u; l < n; ++l) {
            bool same = ((picks[l >> 3] >> ((l & 7u) * 4u)) & 0xFu) == chosen;
            if (same && l < k) earlier += 1u;
            if (same) copies += 1u;
        }
        if (earlier != 0u) continue;
        float ris = total / candidate_target[own + chosen];
        vec4 g = candidate_value[own + chosen];
        emit(first + k, z, z_ng, candidate_slot[own + chosen], g.rgb * (ris * float(copies)),
             g.a, scale);
    }
#endif
}
