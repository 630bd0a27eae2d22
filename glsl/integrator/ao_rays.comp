#version 460
// Ambient-occlusion rays: ao_rays cosine-distributed directions about the viewer-facing
// geometric normal at each primary hit, reaching ao_radius. A missed primary ray gets
// empty rays (tmax = 0) so every pixel owns exactly ao_rays slots.
#include "grid.glsl"
#include "geometry.glsl"
#include "frame.glsl"
#include "random.glsl"

layout(push_constant) uniform Push {
    FrameParams frame;
    BUFFER_REF(RaysInRef, rays)
    BUFFER_REF(HitsInRef, hits)
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(RaysOutRef, ao_rays)
};
BUFFER_BINDING(0, readonly, Ray, rays)
BUFFER_BINDING(1, readonly, Hit, hits)
BUFFER_BINDING(2, readonly, Triangle, triangles)
BUFFER_BINDING(3, writeonly, Ray, ao_rays)

const float PI = 3.14159265358979;

// An orthonormal basis around unit n (Duff et al. 2017, "Building an Orthonormal Basis,
// Revisited").
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
    Hit hit = hits.data[i];
    Ray primary = rays.data[i];
    if (hit.triangle == MISS) {
        for (uint k = 0; k < frame.ao_rays; ++k) {
            ao_rays.data[i * frame.ao_rays + k] = Ray(primary.origin, 0.0, primary.dir, 0.0);
        }
        return;
    }
    Triangle tri = triangles.data[hit.triangle];
    vec3 n = normalize(triangle_normal(tri));
    if (dot(n, primary.dir) > 0.0) n = -n;
    vec3 p = primary.origin + hit.t * primary.dir + frame.ray_epsilon * n;
    vec3 t, b;
    basis(n, t, b);
    for (uint k = 0; k < frame.ao_rays; ++k) {
        uint dim = 2u + 2u * k;
        float u1 = random01(pixel, frame.sample_index, dim, frame.seed);
        float u2 = random01(pixel, frame.sample_index, dim + 1u, frame.seed);
        // Cosine-weighted hemisphere (Malley's method).
        float r = sqrt(u1);
        float phi = 2.0 * PI * u2;
        vec3 local = vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u1)));
        vec3 dir = normalize(local.x * t + local.y * b + local.z * n);
        ao_rays.data[i * frame.ao_rays + k] = Ray(p, 0.0, dir, frame.ao_radius);
    }
}
