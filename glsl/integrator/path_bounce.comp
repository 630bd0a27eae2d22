#version 460
// One bounce of the `path` integrator (PDACRT §3.1: diffuse path tracing, 7 bounces,
// Lambertian shading): add the emitted radiance at the hit, weighted by the path
// throughput; multiply the throughput by the albedo (cosine-weighted sampling of a
// Lambertian BSDF cancels the cos/π/pdf factors); write the next ray. Paths that missed,
// or have no bounce left, get empty rays (tmax = 0), which every tracer drops at once.
// Estimates emission-only light transport without next-event estimation: the
// physically based path tracer with NEE and MIS is the `pt` integrator.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"
#include "film_sum.glsl"
#include "material.glsl"
#include "random.glsl"

layout(push_constant) uniform Push {
    FrameParams frame;
    BUFFER_REF(RaysRef, rays)
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(UintsInRef, triangle_material)
    BUFFER_REF(MaterialsInRef, materials)
    BUFFER_REF(Vec4sRef, throughput)
    BUFFER_REF(Vec4sRef, accum)
};
BUFFER_BINDING(0, , Ray, rays)
BUFFER_BINDING(1, readonly, Hit, hits)
BUFFER_BINDING(2, readonly, Triangle, triangles)
BUFFER_BINDING(3, readonly, uint, triangle_material)
BUFFER_BINDING(4, readonly, Material, materials)
BUFFER_BINDING(5, , vec4, throughput)
BUFFER_BINDING(6, , vec4, accum)

const float PI = 3.14159265358979;
// Bounces after the camera hit; the camera hit is bounce 0.
const uint MAX_BOUNCES = 7u;

void basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

void main() {
    uint i = linear_invocation_id();
    if (i >= frame.pixel_count) return;
    uint pixel = frame.pixel_offset + i;
    vec3 t_in = frame.bounce == 0u ? vec3(1.0) : throughput.data[i].rgb;
    Ray ray = rays.data[i];
    Hit hit = hits.data[i];
    vec4 added = vec4(0.0, 0.0, 0.0, frame.bounce == 0u ? 1.0 : 0.0);
    if (hit.triangle == MISS || ray.tmax == 0.0) {
        rays.data[i] = Ray(ray.origin, 0.0, ray.dir, 0.0);
        throughput.data[i] = vec4(0.0);
        FILM_ADD(accum.data, pixel, frame.width * frame.height, added);
        return;
    }
    Triangle tri = triangles.data[hit.triangle];
    Material m = materials.data[triangle_material.data[hit.triangle]];
    added.rgb = t_in * m.emission.rgb;
    FILM_ADD(accum.data, pixel, frame.width * frame.height, added);
    vec3 t_out = t_in * m.diffuse.rgb;
    if (frame.bounce >= MAX_BOUNCES || max(t_out.r, max(t_out.g, t_out.b)) == 0.0) {
        rays.data[i] = Ray(ray.origin, 0.0, ray.dir, 0.0);
        throughput.data[i] = vec4(0.0);
        return;
    }
    vec3 n = normalize(triangle_normal(tri));
    if (dot(n, ray.dir) > 0.0) n = -n;
    vec3 p = ray.origin + hit.t * ray.dir + frame.ray_epsilon * n;
    uint dim = 2u + 2u * frame.bounce;
    float u1 = random01(pixel, frame.sample_index, dim, frame.seed);
    float u2 = random01(pixel, frame.sample_index, dim + 1u, frame.seed);
    vec3 tt, bb;
    basis(n, tt, bb);
    float r = sqrt(u1);
    float phi = 2.0 * PI * u2;
    vec3 d = normalize(r * cos(phi) * tt + r * sin(phi) * bb + sqrt(max(0.0, 1.0 - u1)) * n);
    rays.data[i] = Ray(p, 0.0, d, 1.0 / 0.0);
    throughput.data[i] = vec4(t_out, 0.0);
}
