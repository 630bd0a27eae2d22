// Surfaces of the scene (src/bidir/scene.rs `CpuScene`): needs `Triangle triangles[]`.
// Define LVC_SHADING_NORMALS and declare `vec4 normals[]` for interpolated normals.
#ifndef SPLITRAY_LVC_SURFACE_GLSL
#define SPLITRAY_LVC_SURFACE_GLSL

// Unit geometric normal: the triangle's front, normalize(e1 x e2).
vec3 triangle_normal(uint tri) {
    return normalize(triangle_normal(triangles[tri]));
}

float triangle_area(uint tri) {
    return 0.5 * length(triangle_normal(triangles[tri]));
}

#ifdef LVC_SHADING_NORMALS
// The interpolated vertex normal at a hit, flipped to ng's side; ng where the mesh has none.
vec3 shading_normal(Hit hit, vec3 ng) {
    vec4 n0 = normals[3u * hit.triangle];
    if (n0.w == 0.0) return ng;
    vec3 n1 = normals[3u * hit.triangle + 1u].xyz;
    vec3 n2 = normals[3u * hit.triangle + 2u].xyz;
    vec3 n = (1.0 - hit.u - hit.v) * n0.xyz + hit.u * n1 + hit.v * n2;
    if (!(dot(n, n) > 0.0)) return ng;
    vec3 ns = normalize(n);
    return dot(ns, ng) < 0.0 ? -ns : ns;
}
#endif

#endif
