//! CPU twins of the GPU tracers: the same intersection arithmetic, on the host.

use glam::Vec3;
use rayon::prelude::*;

use super::types::{GpuTriangle, Hit, Ray, MISS};

/// Möller–Trumbore, mirroring `intersect_triangle` in glsl/common/geometry.glsl operation
/// for operation. Returns t in (tmin, tmax) or +inf, and the barycentrics (u, v).
#[inline]
pub fn intersect_triangle(
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
    tri: &GpuTriangle,
) -> (f32, f32, f32) {
    let (v0, e1, e2) = (tri.v0(), tri.e1(), tri.e2());
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return (f32::INFINITY, 0.0, 0.0);
    }
    let inv_det = 1.0 / det;
    let s = o - v0;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return (f32::INFINITY, u, 0.0);
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return (f32::INFINITY, u, v);
    }
    let t = e2.dot(q) * inv_det;
    if t > tmin && t < tmax {
        (t, u, v)
    } else {
        (f32::INFINITY, u, v)
    }
}

/// Closest hit of one ray by testing every triangle; ties go to the smaller index.
pub fn closest_hit(ray: &Ray, triangles: &[GpuTriangle]) -> Hit {
    // An empty segment (tmax <= tmin, NaN included) meets nothing; `f32::min` below would
    // otherwise take a NaN tmax for an unbounded one.
    if ray.is_empty() {
        return Hit::NONE;
    }
    let o = Vec3::from(ray.origin);
    let d = Vec3::from(ray.dir);
    let mut best = Hit::NONE;
    for (i, tri) in triangles.iter().enumerate() {
        let (t, u, v) = intersect_triangle(o, d, ray.tmin, ray.tmax.min(best.t), tri);
        if t < best.t {
            best = Hit {
                t,
                triangle: i as u32,
                u,
                v,
            };
        }
    }
    best
}

/// Whether anything blocks the ray within (tmin, tmax).
pub fn occluded(ray: &Ray, triangles: &[GpuTriangle]) -> bool {
    let o = Vec3::from(ray.origin);
    let d = Vec3::from(ray.dir);
    triangles.iter().any(|tri| {
        intersect_triangle(o, d, ray.tmin, ray.tmax, tri)
            .0
            .is_finite()
    })
}

/// Brute-force closest hits of many rays, in parallel on the CPU (in chunks, each a
/// span on its worker's timeline track).
pub fn closest_hits(rays: &[Ray], triangles: &[GpuTriangle]) -> Vec<Hit> {
    rays.par_chunks(4096)
        .flat_map_iter(|chunk| {
            let _span = tracing::info_span!("cpu closest hits", rays = chunk.len()).entered();
            chunk
                .iter()
                .map(|r| closest_hit(r, triangles))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// `true` when two hit records agree: both miss, or both hit with t equal within
/// `rel_tol` (relative) and the same triangle — unless `allow_ties`, which also accepts
/// a different triangle at the same t (two triangles meeting exactly where the ray hits).
pub fn same_hit(a: &Hit, b: &Hit, rel_tol: f32, allow_ties: bool) -> bool {
    if a.triangle == MISS || b.triangle == MISS {
        return a.triangle == b.triangle;
    }
    let close = (a.t - b.t).abs() <= rel_tol * a.t.abs().max(b.t.abs());
    close && (allow_ties || a.triangle == b.triangle)
}
