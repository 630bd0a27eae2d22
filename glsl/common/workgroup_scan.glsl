// A prefix scan of a short array by one workgroup: each invocation sums a contiguous run
// of the items, one invocation scans the WORKGROUP_SIZE run sums in shared memory, and
// every invocation then scans its run from its offset. Two workgroup barriers; no
// subgroup operations. A macro because the arrays may be descriptor bindings or buffer
// references (address.glsl), which a GLSL function cannot take as parameters.
//
// WORKGROUP_SCAN(SRC, DST, N, PREDICATE, INCLUSIVE): SRC and DST are arrays (`x.data`),
// which may be the same; each item is read before it is written, by the invocation that
// writes it. PREDICATE scans (x != 0) instead of x. Other invocations' writes to SRC
// must be visible before it (memoryBarrierBuffer and barrier, or a pipeline barrier);
// DST is written when it returns, visible to the others after another such barrier.
// Needs grid.glsl.
#ifndef SPLITRAY_WORKGROUP_SCAN_GLSL
#define SPLITRAY_WORKGROUP_SCAN_GLSL

shared uint workgroup_scan_runs[WORKGROUP_SIZE];

#define WORKGROUP_SCAN_ITEM(x, predicate) ((predicate) ? uint((x) != 0u) : (x))

#define WORKGROUP_SCAN(SRC, DST, N, PREDICATE, INCLUSIVE)                              \
    {                                                                                  \
        uint ws_n = (N);                                                               \
        uint ws_lid = gl_LocalInvocationID.x;                                          \
        uint ws_per = (ws_n + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;                   \
        uint ws_begin = min(ws_lid * ws_per, ws_n);                                    \
        uint ws_end = min(ws_begin + ws_per, ws_n);                                    \
        uint ws_sum = 0u;                                                              \
        for (uint i = ws_begin; i < ws_end; ++i)                                       \
            ws_sum += WORKGROUP_SCAN_ITEM(SRC[i], PREDICATE);                          \
        workgroup_scan_runs[ws_lid] = ws_sum;                                          \
        barrier();                                                                     \
        if (ws_lid == 0u) {                                                            \
            uint ws_total = 0u;                                                        \
            for (uint w = 0u; w < WORKGROUP_SIZE; ++w) {                               \
                uint ws_v = workgroup_scan_runs[w];                                    \
                workgroup_scan_runs[w] = ws_total;                                     \
                ws_total += ws_v;                                                      \
            }                                                                          \
        }                                                                              \
        barrier();                                                                     \
        uint ws_run = workgroup_scan_runs[ws_lid];                                     \
        for (uint i = ws_begin; i < ws_end; ++i) {                                     \
            uint ws_v = WORKGROUP_SCAN_ITEM(SRC[i], PREDICATE);                        \
            DST[i] = (INCLUSIVE) ? ws_run + ws_v : ws_run;                             \
            ws_run += ws_v;                                                            \
        }                                                                              \
    }

#endif
