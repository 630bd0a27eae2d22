#version 460
// Closest-hit and occlusion queries through the driver's own acceleration structure
// (VK_KHR_ray_query): `--tracer ray-query`. One invocation per ray.
//
// Needs GL_EXT_ray_query, so the pipeline is created only on devices that offer ray
// queries (src/trace/ray_query.rs); elsewhere this module is compiled but never used.
// The geometry is opaque, so rayQueryProceedEXT never stops on a candidate and the
// committed intersection is the closest one. Ties in t are broken by the driver, not
// by triangle index.
// With OCCLUSION defined, the query ends at the first hit found (shadow rays).
//! variant occlusion: OCCLUSION=1
#extension GL_EXT_ray_query : require
#include "grid.glsl"
#include "geometry.glsl"

layout(set = 0, binding = 2) uniform accelerationStructureEXT scene;
struct RayQueryPush {
    uint ray_count;
};
layout(push_constant) uniform Push {
    RayQueryPush pc;
    BUFFER_REF(RaysInRef, rays)
    BUFFER_REF(HitsOutRef, hits)
};
BUFFER_BINDING(0, readonly, Ray, rays)
BUFFER_BINDING(1, writeonly, Hit, hits)

void main() {
    uint ray_index = linear_invocation_id();
    if (ray_index >= pc.ray_count) return;
    Ray ray = rays.data[ray_index];
    uint flags = gl_RayFlagsOpaqueEXT;
#ifdef OCCLUSION
    flags |= gl_RayFlagsTerminateOnFirstHitEXT;
#endif
    // Ray queries need 0 <= tmin <= tmax; +inf is kept finite for drivers' sake.
    float tmin = max(ray.tmin, 0.0);
    float tmax = min(ray.tmax, 3.402823466e38);
    Hit hit = Hit(1.0 / 0.0, MISS, 0.0, 0.0);
    // Rays that meet nothing in every tracer never reach the driver, for which they are
    // undefined (VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06348 to -06351): an empty
    // segment, tested before the clamps above, which may turn a NaN bound into the
    // other operand (GLSL's min and max on NaN); and a NaN or infinite origin or
    // direction component.
    if (!ray_is_empty(ray) && finite(ray.origin) && finite(ray.dir) && tmax > tmin) {
        rayQueryEXT query;
        rayQueryInitializeEXT(query, scene, flags, 0xFF, ray.origin, tmin, ray.dir, tmax);
        while (rayQueryProceedEXT(query)) {
        }
        if (rayQueryGetIntersectionTypeEXT(query, true) ==
            gl_RayQueryCommittedIntersectionTriangleEXT) {
            vec2 uv = rayQueryGetIntersectionBarycentricsEXT(query, true);
            hit = Hit(rayQueryGetIntersectionTEXT(query, true),
                      uint(rayQueryGetIntersectionPrimitiveIndexEXT(query, true)), uv.x, uv.y);
        }
    }
    hits.data[ray_index] = hit;
}
