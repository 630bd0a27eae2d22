#version 460
#ifdef ATOMIC
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#endif
// Segmented naive intersection, Algorithm 3 lines 2–10: one workgroup per terminal node
// (segment); each invocation takes one of the segment's rays at a time (line 3) while
// the workgroup stages the segment's triangles through shared memory in batches of BATCH
// (line 4) and every ray tests the batch (lines 5–7). The result per buffer entry — the
// closest (t, triangle) of that ray within that segment — is reduced per ray afterwards
// (lines 12–13). Ties go to the smaller triangle index, as in every splitray tracer.
//
// The `direct` variant reads each triangle straight from the triangle buffer instead of
// staging it (no shared memory, no barrier). Workgroup barriers are very slow on CPU
// devices (lavapipe), where shared memory is no nearer than any other memory; the
// tracer picks the variant per device (PdacrtParams::stage_triangles). Free of
// barriers, it can also stop early in occlusion mode: an invocation leaves a segment's
// triangles once each of its rays has some hit (the staged variant's invocations must
// keep meeting at its barriers).
//
// The `atomic` variants (FlushReduce::AtomicMin) replace the per-entry outputs and the
// sort by ray id + segmented arg-min that follows (Algorithm 3 lines 12–13) with one
// 64-bit atomicMin per entry into the chunk's packed closest hits: (order-preserving t
// bits << 32 | triangle), so the smaller t wins and equal t goes to the smaller
// triangle index, exactly the arg-min's order (the layout is in pdacrt.glsl).
//! variant direct: DIRECT=1
//! variant atomic: ATOMIC=1
//! variant direct_atomic: DIRECT=1 ATOMIC=1
#include "grid.glsl"
#include "geometry.glsl"
#include "pdacrt.glsl"

layout(constant_id = 1) const uint BATCH = 256;

#ifdef ATOMIC
layout(buffer_reference, std430, buffer_reference_align = 8) buffer PackedHitsRef { uint64_t data[]; };
#endif

struct IntersectPush {
    uint segment_count;
    uint ray_offset;
    uint occlusion;  // 1 in occlusion mode (any hit will do; see the direct variant)
};
layout(push_constant) uniform Push {
    IntersectPush pc;
    BUFFER_REF(TrianglesInRef, triangles)
    BUFFER_REF(RaysInRef, rays)
    BUFFER_REF(SegmentsInRef, segments)
    BUFFER_REF(UintsInRef, term_tris)
    BUFFER_REF(UintsInRef, term_rays)
#ifdef ATOMIC
    // The hit buffer, holding the closest hits so far (BEST_SLOT in pdacrt.glsl).
    BUFFER_REF(PackedHitsRef, best_packed)
#else
    BUFFER_REF(FloatsOutRef, entry_t)
    BUFFER_REF(UintsOutRef, entry_tri)
#endif
};
BUFFER_BINDING(0, readonly, Triangle, triangles)
BUFFER_BINDING(1, readonly, Ray, rays)
BUFFER_BINDING(2, readonly, Segment, segments)
BUFFER_BINDING(3, readonly, uint, term_tris)
BUFFER_BINDING(4, readonly, uint, term_rays)
#ifdef ATOMIC
BUFFER_BINDING(5, , uint64_t, best_packed)
#else
BUFFER_BINDING(5, writeonly, float, entry_t)
BUFFER_BINDING(6, writeonly, uint, entry_tri)
#endif

#ifdef ATOMIC
// A closest hit packed for 64-bit atomicMin: smaller t first, then smaller triangle.
uint64_t pack_hit(float t, uint tri) {
    return (uint64_t(ordered_bits(t)) << 32) | uint64_t(tri);
}

// Records entry `entry` (ray `ray` of the chunk): its closest hit within the segment.
void record(uint entry, uint ray, float t, uint tri) {
    if (tri != MISS) atomicMin(best_packed.data[BEST_SLOT(pc.ray_offset + ray)], pack_hit(t, tri));
}
#else
void record(uint entry, uint ray, float t, uint tri) {
    entry_t.data[entry] = t;
    entry_tri.data[entry] = tri;
}
#endif

#ifndef DIRECT
shared Triangle staged[BATCH];
shared uint staged_id[BATCH];
#endif

#ifdef DIRECT
// Rays per invocation: a segment holds at most 8N rays (PdacrtParams::max_segment_rays),
// so every invocation keeps its share in registers and each triangle is loaded once for
// up to 8 rays instead of once per ray.
#define RAYS_PER_INVOCATION 8u

void main() {
    uint seg = linear_group_id();
    if (seg >= pc.segment_count) return;
    Segment s = segments.data[seg];
    uint lid = gl_LocalInvocationID.x;
    uint round_rays = RAYS_PER_INVOCATION * WORKGROUP_SIZE;
    for (uint ray_base = 0u; ray_base < s.ray_count; ray_base += round_rays) {
        // Each ray's part of the triangle test is done once, here, not per triangle.
        ShearedRay r[RAYS_PER_INVOCATION];
        vec2 segment[RAYS_PER_INVOCATION];  // (tmin, tmax)
        uint ray_id[RAYS_PER_INVOCATION];
        float best_t[RAYS_PER_INVOCATION];
        uint best[RAYS_PER_INVOCATION];
        uint mine = 0u;  // rays of this round held by this invocation: k = base + lid + m·N
        for (uint m = 0u; m < RAYS_PER_INVOCATION; ++m) {
            uint k = ray_base + lid + m * WORKGROUP_SIZE;
            best_t[m] = 1.0 / 0.0;
            best[m] = MISS;
            if (k < s.ray_count) {
                ray_id[m] = term_rays.data[s.ray_start + k];
                Ray ray = rays.data[pc.ray_offset + ray_id[m]];
                r[m] = shear_ray(ray.origin, ray.dir);
                segment[m] = vec2(ray.tmin, ray.tmax);
                mine = m + 1u;
            }
        }
        if (mine == 0u) break;
        for (uint j = 0u; j < s.tri_count; ++j) {
            if (pc.occlusion != 0u) {
                bool all_hit = true;
                for (uint m = 0u; m < mine; ++m) all_hit = all_hit && best[m] != MISS;
                if (all_hit) break;
            }
            uint id = term_tris.data[s.tri_start + j];
            Triangle tri = triangles.data[id];
            for (uint m = 0u; m < RAYS_PER_INVOCATION; ++m) {
                if (m >= mine) break;
                float u, v;
                float t = intersect_sheared(r[m], segment[m].x, segment[m].y, tri.v0.xyz,
                                            tri.v1.xyz, tri.v2.xyz, u, v);
                if (t < best_t[m] || (t == best_t[m] && t < 1.0 / 0.0 && id < best[m])) {
                    best_t[m] = t;
                    best[m] = id;
                }
            }
        }
        for (uint m = 0u; m < mine; ++m) {
            record(s.ray_start + ray_base + lid + m * WORKGROUP_SIZE, ray_id[m], best_t[m], best[m]);
        }
    }
}
#else
void main() {
    uint seg = linear_group_id();
    // Uniform per workgroup: the whole group leaves together, before any barrier.
    if (seg >= pc.segment_count) return;
    Segment s = segments.data[seg];
    uint lid = gl_LocalInvocationID.x;
    for (uint ray_base = 0u; ray_base < s.ray_count; ray_base += WORKGROUP_SIZE) {
        uint k = ray_base + lid;
        bool has_ray = k < s.ray_count;
        Ray r;
        uint ray_id = 0u;
        if (has_ray) {
            ray_id = term_rays.data[s.ray_start + k];
            r = rays.data[pc.ray_offset + ray_id];
        }
        ShearedRay sheared = shear_ray(r.origin, r.dir);
        float best_t = 1.0 / 0.0;
        uint best = MISS;
        for (uint tri_base = 0u; tri_base < s.tri_count; tri_base += BATCH) {
            uint count = min(BATCH, s.tri_count - tri_base);
            for (uint j = lid; j < count; j += WORKGROUP_SIZE) {
                uint id = term_tris.data[s.tri_start + tri_base + j];
                staged[j] = triangles.data[id];
                staged_id[j] = id;
            }
            barrier();
            if (has_ray) {
                for (uint j = 0u; j < count; ++j) {
                    float u, v;
                    float t = intersect_sheared(sheared, r.tmin, r.tmax, staged[j].v0.xyz,
                                                staged[j].v1.xyz, staged[j].v2.xyz, u, v);
                    if (t < best_t || (t == best_t && t < 1.0 / 0.0 && staged_id[j] < best)) {
                        best_t = t;
                        best = staged_id[j];
                    }
                }
            }
            barrier();
        }
        if (has_ray) record(s.ray_start + k, ray_id, best_t, best);
    }
}
#endif
