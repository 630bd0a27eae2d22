// Buffers by device address: how a kernel takes a buffer that may be larger than one
// storage binding (maxStorageBufferRange: 128 MiB on lavapipe). A buffer reference
// reaches anything a VkBuffer holds (src/vk/buffer.rs: up to maxBufferSize and
// maxMemoryAllocationSize).
//
// A kernel declares such a buffer as a buffer_reference type (its array named `data`;
// the types here and in geometry.glsl end in `Ref`, with `In` for read-only and `Out`
// for write-only views) and puts a member of that type at the end of its push-constant
// block, after its values. The host binds the buffer like any other (src/vk/reflect.rs):
// a kernel with k references takes its bindings 0..k by address, in order, and declares
// bindings k..n, if any, as descriptors.
//
//     layout(push_constant) uniform Push {
//         uint n;                    // the values first: the Rust push struct
//         TrianglesInRef triangles;  // binding 0, by address
//         UintsRef ids;              // binding 1, by address
//     } pc;
//     layout(std430, set = 0, binding = 2) readonly buffer Small { uint small[]; };
//     ... pc.triangles.data[i] ...
//
// Kernels that take every buffer by address need push-constant room for 8 bytes per
// buffer beside their values (256 bytes on lavapipe and NVIDIA, and on every Vulkan 1.4
// device; src/vk/pipeline.rs names a kernel that does not fit).
// Indices stay 32-bit: element counts are below 2^31, the byte offsets they make are
// 64-bit. Two views of one buffer are one reference cast through its address
// (`Other(uvec2(pc.ref))`, GL_EXT_buffer_reference_uvec2).
#ifndef SPLITRAY_ADDRESS_GLSL
#define SPLITRAY_ADDRESS_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#ifdef SPLITRAY_DESCRIPTORS
#define BUFFER_REF(RefType, name)
#define BUFFER_BINDING(b, qualifiers, Elem, name) \
    layout(std430, set = 0, binding = b) qualifiers buffer name##_binding { Elem data[]; } name;
#else
#define BUFFER_REF(RefType, name) RefType name;
#define BUFFER_BINDING(b, qualifiers, Elem, name)
#endif

layout(buffer_reference, std430, buffer_reference_align = 4) buffer UintsRef { uint data[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer UintsInRef { uint data[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer UintsOutRef { uint data[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer FloatsRef { float data[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer FloatsInRef { float data[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer FloatsOutRef { float data[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) buffer Uvec2sRef { uvec2 data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Uvec4sRef { uvec4 data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Uvec4sInRef { uvec4 data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Vec4sRef { vec4 data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Vec4sInRef { vec4 data[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer Vec4sOutRef { vec4 data[]; };

#endif
