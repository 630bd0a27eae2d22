// Camera and per-pass parameters shared by the integrator kernels, passed as push
// constants (128 bytes, the size every device offers). `FrameParams` in
// src/integrator/gpu_types.rs is the Rust side; tests/suite/render.rs checks the two agree.
#ifndef SPLITRAY_FRAME_GLSL
#define SPLITRAY_FRAME_GLSL

struct FrameParams {
    vec4 origin;        // xyz camera position
    vec4 forward;       // xyz unit forward
    vec4 right;         // xyz right, scaled by the image plane's half width at distance 1
    vec4 up;            // xyz up, scaled by the half height
    uint width;
    uint height;
    uint sample_index;  // which sample of the pixel this pass takes
    uint seed;
    uint pixel_offset;  // first pixel of this chunk
    uint pixel_count;   // pixels in this chunk
    uint jitter;        // 0: through pixel centres; 1: uniformly jittered in the pixel
    uint ao_rays;       // ambient-occlusion rays per hit
    float ao_radius;
    float ray_epsilon;  // offset of secondary-ray origins (Aabb::ray_epsilon)
    uint bounce;        // path integrator: which bounce this pass shades (0 = camera hit)
    uint pad0;
    vec4 light;         // shadow integrator: point light position, w = intensity (W/sr)
};

#endif
