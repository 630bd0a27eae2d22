#version 460
// Child sizes, Algorithm 2 lines 10–11: after reduce-by-key (run-length encoding) of the
// sorted status keys, each run's key node·4 + code indexes the per-node, per-code count
// table directly. (The paper sums codes and divides by the code; counting runs directly
// is the same result and also works for code 0.)
#include "grid.glsl"
#include "address.glsl"

struct MaxRunsPush {
    uint max_runs;
};
layout(push_constant) uniform Push {
    MaxRunsPush pc;
    BUFFER_REF(UintsInRef, run_keys)
    BUFFER_REF(UintsInRef, run_counts)
    BUFFER_REF(UintsInRef, run_total)  // one word
    BUFFER_REF(UintsOutRef, counts)

};
BUFFER_BINDING(0, readonly, uint, run_keys)
BUFFER_BINDING(1, readonly, uint, run_counts)
BUFFER_BINDING(2, readonly, uint, run_total)
BUFFER_BINDING(3, writeonly, uint, counts)

void main() {
    uint i = linear_invocation_id();
    if (i >= min(run_total.data[0], pc.max_runs)) return;
    counts.data[run_keys.data[i]] = run_counts.data[i];
}
