#version 460
// Test kernel: writes every field of BsdfParams as a float, in declaration order (36 per
// record), so tests/suite/bsdf_gpu.rs can prove the Rust and GLSL layouts agree. Also echoes
// the material-key helpers for key `keys[i]`: type and id.
#include "grid.glsl"
#include "bsdf.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Params { BsdfParams params[]; };
layout(std430, set = 0, binding = 1) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Out { float fields[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = linear_invocation_id();
    if (i >= pc.n) return;
    uint o = i * 38u;
    BsdfParams p = params[i];
    for (uint k = 0u; k < BSDF_MAX_LAYERS; ++k) {
        BsdfLayer l = p.layers[k];
        fields[o + 0u] = l.tint_weight.x;
        fields[o + 1u] = l.tint_weight.y;
        fields[o + 2u] = l.tint_weight.z;
        fields[o + 3u] = l.tint_weight.w;
        fields[o + 4u] = float(l.kind);
        fields[o + 5u] = float(l.distribution);
        fields[o + 6u] = l.roughness;
        fields[o + 7u] = l.ior;
        o += 8u;
    }
    fields[o + 0u] = float(p.count);
    fields[o + 1u] = float(p.pad0);
    fields[o + 2u] = float(p.pad1);
    fields[o + 3u] = float(p.pad2);
    fields[o + 4u] = float(material_key_type(keys[i]));
    fields[o + 5u] = float(material_key_id(keys[i]));
}
