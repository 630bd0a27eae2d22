// Material records as the integrators read them (src/integrator/gpu.rs `GpuMaterial`).
#ifndef SPLITRAY_MATERIAL_GLSL
#define SPLITRAY_MATERIAL_GLSL

struct Material {
    vec4 diffuse;   // rgb albedo
    vec4 emission;  // rgb emitted radiance
};

#include "address.glsl"
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer MaterialsInRef { Material data[]; };

#endif
