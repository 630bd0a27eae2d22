#version 460
// Light pass (Algorithm 7, line 2): a light subpath's first vertex per light path of the
// chunk: a point on a light chosen by power and a direction leaving it (cosine-weighted,
// uniform for a point light), with the random numbers of src/bidir/walk.rs
// `light_subpath` (index = light path of its pass, sample = pass), so that the CPU walk
// is its twin. Paths that cannot start (no light, max_depth <= 1, a zero density) get
// a ray nothing hits.
#include "grid.glsl"
#include "geometry.glsl"
#include "random.glsl"
#include "bsdf.glsl"
#include "../pt/pt.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push {
    LvcPush P;
    BUFFER_REF(LvcConstantsInRef, constants)
    BUFFER_REF(LightsInRef, lights)
    BUFFER_REF(FloatsInRef, light_cdf)
    BUFFER_REF(RaysOutRef, rays)
    BUFFER_REF(UintsOutRef, live_ids)
    BUFFER_REF(WalkStatesOutRef, paths)
    BUFFER_REF(UintsOutRef, vertex_count)
};
BUFFER_BINDING(0, readonly, LvcConstants, constants)
BUFFER_BINDING(1, readonly, Light, lights)
BUFFER_BINDING(2, readonly, float, light_cdf)
BUFFER_BINDING(3, writeonly, Ray, rays)
BUFFER_BINDING(4, writeonly, uint, live_ids)
BUFFER_BINDING(5, writeonly, WalkState, paths)
BUFFER_BINDING(6, writeonly, uint, vertex_count)
#define C constants.data[0]

#include "lvc_lights.glsl"

void main() {
    uint l = linear_invocation_id();
    if (l >= P.path_count) return;
    uint index = l % C.light_paths;
    uint pass = P.first_pass + l / C.light_paths;
    live_ids.data[l] = l;
    vertex_count.data[l] = 0u;

    WalkState s;
    s.beta = vec3(0.0);
    s.d_vcm = 0.0;
    s.carried = vec3(1.0);
    s.d_vc = 0.0;
    s.prev_p = vec3(0.0);
    s.pending_fwd = 0.0;
    s.prev_ng = vec3(0.0);
    s.pending_rev = 0.0;
    s.pending_count = 0.0;
    s.depth = 0u;
    s.flags = 0u;
    s.eta2 = 1.0;
    Ray ray = no_ray();

    bool room = C.max_depth < 0 || 1 < C.max_depth;
    if (room && C.light_count > 0u) {
        vec3 u = vec3(random01(index, pass, emission_dim(DIM_EMIT_PICK), C.seed),
                      random01(index, pass, emission_dim(DIM_EMIT_POINT), C.seed),
                      random01(index, pass, emission_dim(DIM_EMIT_POINT + 1u), C.seed));
        float u3 = random01(index, pass, emission_dim(DIM_EMIT_DIRECTION), C.seed);
        float u4 = random01(index, pass, emission_dim(DIM_EMIT_DIRECTION + 1u), C.seed);
        LightPoint q = lvc_sample_light(u, C.light_count);
        if (q.valid) {
            vec3 dir = q.delta ? uniform_sphere(u3, u4)
                               : bsdf_to_world(bsdf_frame(q.n), cosine_hemisphere(u3, u4));
            float cos_out = q.delta ? 1.0 : dot(q.n, dir);
            float pdf_dir = q.delta ? uniform_sphere_pdf() : max(cos_out, 0.0) * LVC_INV_PI;
            if (pdf_dir > 0.0 && cos_out > 0.0) {
                s.beta = q.radiance * (cos_out / (q.pdf_area * pdf_dir));
                // Emission densities (EmissionDensities): direct, emit * direction.
                s.d_vcm = q.pdf_area;
                s.d_vc = q.pdf_area * pdf_dir;
                s.prev_p = q.p;
                s.prev_ng = q.n;
                s.flags = WALK_PENDING_EMISSION | (q.delta ? WALK_DELTA_POSITION : 0u);
                ray = Ray(offset_ray_origin(q.p, q.n, dir, C.ray_epsilon), 0.0, dir, 1.0 / 0.0);
            }
        }
    }
    rays.data[l] = ray;
    paths.data[l] = s;
}
