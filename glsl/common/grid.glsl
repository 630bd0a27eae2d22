// Workgroup size and linear indexing shared by every 1-D kernel.
//
// The workgroup size is specialization constant 0, set from Rust (one source of truth).
// Kernels read WORKGROUP_SIZE, not gl_WorkGroupSize: with SPIR-V 1.6 glslang emits
// LocalSizeId and leaves gl_WorkGroupSize at its default (1,1,1), so it would be wrong.
//
// linear_group_id() undoes the folding of long 1-D launches into 2-D grids that
// `grid_for` (src/vk/command.rs) does when maxComputeWorkGroupCount[0] is exceeded.
#ifndef SPLITRAY_GRID_GLSL
#define SPLITRAY_GRID_GLSL

layout(local_size_x_id = 0) in;
layout(constant_id = 0) const uint WORKGROUP_SIZE = 64;

uint linear_group_id() {
    return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
}

uint linear_invocation_id() {
    return linear_group_id() * WORKGROUP_SIZE + gl_LocalInvocationID.x;
}

#endif
