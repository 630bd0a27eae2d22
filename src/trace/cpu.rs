//! CPU twins of the GPU tracers: the same intersection arithmetic, on the host.

use glam::Vec3;
use rayon::prelude::*;

use super::types::{GpuTriangle, Hit, Ray, MISS};

/// A ray ready for the watertight ray–triangle test (Woop, Benthin and Wald 2013): the
/// per-ray part, computed once for all the triangles it meets. Mirrors `ShearedRay`,
/// `shear_ray` and `intersect_sheared` in glsl/common/geometry.glsl operation for
/// operation (its comment gives the method and why).
#[derive(Clone, Copy, Debug)]
pub struct ShearedRay {
    origin: Vec3,
    /// The axis that becomes z; 3 for a ray that meets nothing (an infinite or NaN origin
    /// or direction, or a zero direction).
    kz: usize,
    /// (sx, sy, sz).
    shear: Vec3,
}

impl ShearedRay {
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Self {
        let ad = d.abs();
        let kz = if ad.x > ad.y {
            if ad.x > ad.z {
                0
            } else {
                2
            }
        } else if ad.y > ad.z {
            1
        } else {
            2
        };
        let dp = permute_to_z(d, kz);
        if !(o.is_finite() && d.is_finite()) || dp.z == 0.0 {
            return Self {
                origin: o,
                kz: 3,
                shear: Vec3::ZERO,
            };
        }
        let sz = 1.0 / dp.z;
        Self {
            origin: o,
            kz,
            shear: Vec3::new(-dp.x * sz, -dp.y * sz, sz),
        }
    }

    /// t in (tmin, tmax) or +inf, and the barycentrics (u, v) of vertices 1 and 2 (zero
    /// for a miss).
    #[inline]
    pub fn intersect(&self, tmin: f32, tmax: f32, tri: &GpuTriangle) -> (f32, f32, f32) {
        const MISSED: (f32, f32, f32) = (f32::INFINITY, 0.0, 0.0);
        if self.kz > 2 {
            return MISSED;
        }
        let [a, b, c] = tri
            .vertices()
            .map(|p| permute_to_z(p - self.origin, self.kz));
        let (sx, sy, sz) = (self.shear.x, self.shear.y, self.shear.z);
        let (ax, ay) = (a.x + sx * a.z, a.y + sy * a.z);
        let (bx, by) = (b.x + sx * b.z, b.y + sy * b.z);
        let (cx, cy) = (c.x + sx * c.z, c.y + sy * c.z);
        let e0 = bx * cy - by * cx;
        let e1 = cx * ay - cy * ax;
        let e2 = ax * by - ay * bx;
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return MISSED;
        }
        let det = e0 + e1 + e2;
        if det == 0.0 {
            return MISSED;
        }
        let scaled_t = (e0 * (sz * a.z) + e1 * (sz * b.z)) + e2 * (sz * c.z);
        let inv_det = 1.0 / det;
        let t = scaled_t * inv_det;
        if !(t > tmin && t < tmax) {
            return MISSED;
        }
        (t, e1 * inv_det, e2 * inv_det)
    }
}

/// The watertight test of one ray and one triangle ([`ShearedRay`]; GLSL twin:
/// `intersect_triangle`). Returns t in (tmin, tmax) or +inf, and the barycentrics (u, v)
/// of vertices 1 and 2 (zero for a miss).
#[inline]
pub fn intersect_triangle(
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
    tri: &GpuTriangle,
) -> (f32, f32, f32) {
    ShearedRay::new(o, d).intersect(tmin, tmax, tri)
}

/// `a` with the axis `kz` last and the other two in cyclic order (`permute_to_z` in
/// glsl/common/geometry.glsl).
#[inline]
fn permute_to_z(a: Vec3, kz: usize) -> Vec3 {
    match kz {
        0 => Vec3::new(a.y, a.z, a.x),
        1 => Vec3::new(a.z, a.x, a.y),
        _ => a,
    }
}

/// Closest hit of one ray by testing every triangle; ties go to the smaller index.
pub fn closest_hit(ray: &Ray, triangles: &[GpuTriangle]) -> Hit {
    // An empty segment (tmax <= tmin, NaN included) meets nothing; `f32::min` below would
    // otherwise take a NaN tmax for an unbounded one.
    if ray.is_empty() {
        return Hit::NONE;
    }
    let sheared = ShearedRay::new(Vec3::from(ray.origin), Vec3::from(ray.dir));
    let mut best = Hit::NONE;
    for (i, tri) in triangles.iter().enumerate() {
        let (t, u, v) = sheared.intersect(ray.tmin, ray.tmax.min(best.t), tri);
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
    let sheared = ShearedRay::new(Vec3::from(ray.origin), Vec3::from(ray.dir));
    triangles
        .iter()
        .any(|tri| sheared.intersect(ray.tmin, ray.tmax, tri).0.is_finite())
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
