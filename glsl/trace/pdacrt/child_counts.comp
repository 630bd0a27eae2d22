#version 460
// Child sizes, Algorithm 2 lines 10–11: after reduce-by-key (run-length encoding) of the
// sorted status keys, each run's key node·4 + code indexes the per-node, per-code count
// table directly. (The paper sums codes and divides by the code; counting runs directly
// is the same result and also works for code 0.)
#include "grid.glsl"

layout(std430, set = 0, binding = 0) readonly buffer RunKeys { uint run_keys[]; };
layout(std430, set = 0, binding = 1) readonly buffer RunCounts { uint run_counts[]; };
layout(std430, set = 0, binding = 2) readonly buffer RunTotal { uint run_total; };
layout(std430, set = 0, binding = 3) writeonly buffer Counts { uint counts[]; };
layout(push_constant) uniform Push { uint max_runs; } pc;

void main() {
    uint i = linear_invocation_id();
    if (i >= min(run_total, pc.max_runs)) return;
    counts[run_keys[i]] = run_counts[i];
}
