// Warps from [0,1)^2 to directions. Mirrored by src/bsdf/sampling.rs.
#ifndef SPLITRAY_SAMPLING_GLSL
#define SPLITRAY_SAMPLING_GLSL

const float SAMPLING_PI = 3.14159265358979323846;
const float ONE_MINUS_EPSILON = 0.99999994;

// Cosine-weighted direction on the +z hemisphere (polar mapping: r = sqrt(u1), phi = 2 pi u2).
vec3 cosine_hemisphere(float u1, float u2) {
    float r = sqrt(u1);
    float phi = 2.0 * SAMPLING_PI * u2;
    float z = sqrt(max(1.0 - u1, 0.0));
    return vec3(r * cos(phi), r * sin(phi), z);
}

float cosine_hemisphere_pdf(float cos_theta) {
    return abs(cos_theta) * (1.0 / SAMPLING_PI);
}

vec3 uniform_sphere(float u1, float u2) {
    float z = 1.0 - 2.0 * u1;
    float r = sqrt(max(1.0 - z * z, 0.0));
    float phi = 2.0 * SAMPLING_PI * u2;
    return vec3(r * cos(phi), r * sin(phi), z);
}

float uniform_sphere_pdf() {
    return 1.0 / (4.0 * SAMPLING_PI);
}

#endif
