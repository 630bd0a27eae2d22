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

/// Below this distance [`same_hit`] compares t in absolute terms (`rel_tol` times it).
/// A hit that close to the ray's origin has t made of the difference of two nearly equal
/// positions (origin and vertex), so its error is the positions' rounding, absolute in
/// scene units, rather than a fraction of t; devices that fuse multiply-adds round it
/// differently from the CPU (an NVIDIA H200: t of 2.6e-5 … 1.3e-3 apart by 4e-10 …
/// 1.7e-8 on a unit-sized triangle soup).
pub const SAME_HIT_NEAR: f32 = 1e-2;

/// `true` when two hit records agree: both miss, or both hit with t equal within
/// `rel_tol` (relative; absolute `rel_tol` × [`SAME_HIT_NEAR`] nearer than that) and the
/// same triangle — unless `allow_ties`, which also accepts a different triangle at the
/// same t (two triangles meeting exactly where the ray hits).
pub fn same_hit(a: &Hit, b: &Hit, rel_tol: f32, allow_ties: bool) -> bool {
    if a.triangle == MISS || b.triangle == MISS {
        return a.triangle == b.triangle;
    }
    let scale = a.t.abs().max(b.t.abs()).max(SAME_HIT_NEAR);
    let close = (a.t - b.t).abs() <= rel_tol * scale;
    close && (allow_ties || a.triangle == b.triangle)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(t: f32, triangle: u32) -> Hit {
        Hit {
            t,
            triangle,
            u: 0.0,
            v: 0.0,
        }
    }

    #[test]
    fn hits_compare_relatively_far_and_absolutely_near() {
        // Far: within rel_tol of t.
        assert!(same_hit(&hit(100.0, 3), &hit(100.0009, 3), 1e-5, false));
        assert!(!same_hit(&hit(100.0, 3), &hit(100.002, 3), 1e-5, false));
        // Near: within rel_tol × SAME_HIT_NEAR = 1e-7, the H200's worst pair included.
        assert!(same_hit(
            &hit(1.2819296e-3, 3),
            &hit(1.2819468e-3, 3),
            1e-5,
            false
        ));
        assert!(same_hit(
            &hit(1.3628605e-4, 3),
            &hit(1.3628286e-4, 3),
            1e-5,
            false
        ));
        assert!(!same_hit(&hit(1e-4, 3), &hit(1.003e-4, 3), 1e-5, false));
        // The triangle, ties and misses as before.
        assert!(!same_hit(&hit(1.0, 3), &hit(1.0, 4), 1e-5, false));
        assert!(same_hit(&hit(1.0, 3), &hit(1.0, 4), 1e-5, true));
        assert!(same_hit(&Hit::NONE, &Hit::NONE, 1e-5, false));
        assert!(!same_hit(&Hit::NONE, &hit(1.0, 3), 1e-5, true));
    }
}
