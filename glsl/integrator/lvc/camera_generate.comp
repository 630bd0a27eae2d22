#version 460
// Camera pass (Algorithm 8, line 2): a camera subpath per pixel and pass of the chunk,
// its ray uniformly jittered in the pixel (a box filter; the random numbers of
// src/bidir/walk.rs `camera_subpath`, index = pixel, sample = pass) and the identity
// active list. max_depth 0 traces nothing.
#include "grid.glsl"
#include "geometry.glsl"
#include "random.glsl"
#include "lvc.glsl"

layout(push_constant) uniform Push { LvcPush P; };
layout(std430, set = 0, binding = 0) readonly buffer Constants { LvcConstants C; };
layout(std430, set = 0, binding = 1) writeonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Active { uint live_ids[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Paths { WalkState paths[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Radiance { vec4 radiance[]; };

void main() {
    uint c = linear_invocation_id();
    if (c >= P.path_count) return;
    uint pixel = P.pixel_offset + c % P.pixel_count;
    uint pass = P.first_pass + c / P.pixel_count;
    float jx = random01(pixel, pass, DIM_CAMERA_JITTER, C.seed);
    float jy = random01(pixel, pass, DIM_CAMERA_JITTER + 1u, C.seed);
    float px = float(pixel % C.width);
    float py = float(pixel / C.width);
    vec3 dir = camera_direction(C, px + jx, py + jy);
    WalkState s;
    s.beta = vec3(1.0);
    s.d_vcm = 1.0 / camera_pdf_direction(C, dir);
    s.carried = vec3(1.0);
    s.d_vc = 0.0;
    s.prev_p = C.origin;
    s.pending_fwd = 0.0;
    s.prev_ng = vec3(0.0);
    s.pending_rev = 0.0;
    s.pending_count = 0.0;
    s.depth = 0u;
    s.flags = 0u;
    s.eta2 = 1.0;
    paths[c] = s;
    live_ids[c] = c;
    radiance[c] = vec4(0.0);
    rays[c] = C.max_depth == 0 ? no_ray() : Ray(C.origin, 0.0, dir, 1.0 / 0.0);
}
