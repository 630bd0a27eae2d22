// Surfaces of the scene (src/bidir/scene.rs `CpuScene`): needs the Triangle buffer
// `triangles` (a BUFFER_REF or BUFFER_BINDING of address.glsl). Define
// LVC_SHADING_NORMALS and declare the vec4 buffer `normals` and the constants `C` for
// interpolated normals.
#ifndef SPLITRAY_LVC_SURFACE_GLSL
#define SPLITRAY_LVC_SURFACE_GLSL

// Unit geometric normal: the triangle's front, normalize(e1 x e2).
vec3 triangle_normal(uint tri) {
    return normalize(triangle_normal(triangles.data[tri]));
}

float triangle_area(uint tri) {
    return 0.5 * length(triangle_normal(triangles.data[tri]));
}

#ifdef LVC_SHADING_NORMALS
// The interpolated vertex normal at a hit, flipped to ng's side; ng where the mesh has none.
vec3 shading_normal(Hit hit, vec3 ng) {
    // Without normals the table is one dummy entry: reading it at a triangle's index
    // would be out of bounds.
    if ((C.flags & LVC_FLAG_NORMALS) == 0u) return ng;
    vec4 n0 = normals.data[3u * hit.triangle];
    if (n0.w == 0.0) return ng;
    vec3 n1 = normals.data[3u * hit.triangle + 1u].xyz;
    vec3 n2 = normals.data[3u * hit.triangle + 2u].xyz;
    vec3 n = (1.0 - hit.u - hit.v) * n0.xyz + hit.u * n1 + hit.v * n2;
    if (!(dot(n, n) > 0.0)) return ng;
    vec3 ns = normalize(n);
    return dot(ns, ng) < 0.0 ? -ns : ns;
}
#endif

#endif
