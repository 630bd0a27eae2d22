//! The scene as the CPU bidirectional integrators see it: `pt`'s tables ([`PtScene`]:
//! triangles, per-triangle materials, BSDF stacks, shading normals, the light table) and
//! the CPU BVH ([`CpuBvh`]), which many rayon threads query at once.
//!
//! Conventions, all `pt`'s (`glsl/integrator/pt/shade.comp`):
//! - the geometric normal is normalize(e1 × e2), the front of a triangle; emitters emit
//!   towards it only;
//! - the shading normal interpolates the mesh's vertex normals with the hit's
//!   barycentrics and is flipped to the geometric normal's side (the geometric normal
//!   where the mesh has none);
//! - a ray leaving a surface starts 1e-4 × the scene's bounding radius away from it along
//!   the geometric normal, on the side it leaves towards; a shadow ray towards a point
//!   ends 1e-4 of its length short of it.

use glam::Vec3;

use super::positive;

use crate::bsdf::BsdfParams;
use crate::integrator::pt::PtScene;
use crate::scene::Scene;
use crate::trace::{CpuBvh, Hit, Ray};

/// The fraction of a shadow ray's length it tests (1 − 1e-4: it ends just short of the
/// far end, which lies on a surface).
pub const SHADOW_RAY_REACH: f32 = 1.0 - 1e-4;

/// Where a ray met a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    pub p: Vec3,
    /// Unit geometric normal (the triangle's front).
    pub ng: Vec3,
    /// Unit shading normal, on the side of `ng`.
    pub ns: Vec3,
    pub triangle: u32,
    pub material: u32,
    /// Distance along the ray.
    pub t: f32,
}

/// `pt`'s scene tables and a BVH over its triangles.
pub struct CpuScene {
    pub tables: PtScene,
    pub bvh: CpuBvh,
    /// Offset of ray origins off surfaces.
    pub ray_epsilon: f32,
}

impl CpuScene {
    pub fn new(scene: &Scene) -> Self {
        Self::from_tables(PtScene::new(scene))
    }

    pub fn from_tables(tables: PtScene) -> Self {
        Self {
            bvh: CpuBvh::new(&tables.triangles),
            ray_epsilon: tables.ray_epsilon,
            tables,
        }
    }

    pub fn bsdf(&self, material: u32) -> &BsdfParams {
        &self.tables.bsdfs[material as usize]
    }

    /// Emitted radiance of a material (front side only).
    pub fn emission(&self, material: u32) -> Vec3 {
        Vec3::from_slice(&self.tables.materials[material as usize].emission[..3])
    }

    /// Whether a material has a non-delta lobe that connections can evaluate.
    pub fn connectible(&self, material: u32) -> bool {
        self.tables.materials[material as usize].all_delta == 0
    }

    /// Area of a triangle (as the light table measures it).
    pub fn triangle_area(&self, triangle: u32) -> f32 {
        0.5 * self.tables.triangles[triangle as usize].normal().length()
    }

    /// The closest surface along the unit direction `dir` from `origin`.
    pub fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<SurfaceHit> {
        let hit = self
            .bvh
            .closest_hit(&Ray::new(origin, dir, 0.0, f32::INFINITY));
        if !hit.is_hit() {
            return None;
        }
        let tri = &self.tables.triangles[hit.triangle as usize];
        let ng = tri.normal().normalize();
        Some(SurfaceHit {
            p: origin + hit.t * dir,
            ng,
            ns: self.shading_normal(&hit, ng),
            triangle: hit.triangle,
            material: self.tables.triangle_material[hit.triangle as usize],
            t: hit.t,
        })
    }

    /// The interpolated vertex normal at a hit, flipped to `ng`'s side; `ng` where the
    /// mesh has no normals.
    fn shading_normal(&self, hit: &Hit, ng: Vec3) -> Vec3 {
        let normals = &self.tables.normals;
        let base = 3 * hit.triangle as usize;
        let Some(n0) = normals.get(base).filter(|n| n[3] != 0.0) else {
            return ng;
        };
        let [n1, n2] = [normals[base + 1], normals[base + 2]];
        let n = (1.0 - hit.u - hit.v) * Vec3::from_slice(&n0[..3])
            + hit.u * Vec3::from_slice(&n1[..3])
            + hit.v * Vec3::from_slice(&n2[..3]);
        if n.length_squared() <= 0.0 {
            return ng;
        }
        let ns = n.normalize();
        if ns.dot(ng) < 0.0 {
            -ns
        } else {
            ns
        }
    }

    /// `p` moved off its surface (geometric normal `ng`) to the side `dir` points to.
    pub fn offset(&self, p: Vec3, ng: Vec3, dir: Vec3) -> Vec3 {
        if ng == Vec3::ZERO {
            return p;
        }
        let eps = if ng.dot(dir) > 0.0 {
            self.ray_epsilon
        } else {
            -self.ray_epsilon
        };
        p + ng * eps
    }

    /// Whether the segment between two points is free: its [`CpuScene::shadow_ray`]
    /// exists and hits nothing.
    pub fn unoccluded(&self, a: Vec3, a_ng: Vec3, b: Vec3, b_ng: Vec3) -> bool {
        self.shadow_ray(a, a_ng, b, b_ng)
            .is_some_and(|ray| !self.bvh.occluded(&ray))
    }

    /// The ray that tests the segment between two points. Each end on a surface (its
    /// geometric normal non-zero) is moved off it towards the other end; a point in space
    /// (the pinhole, a point light: zero normal) stays where it is; the ray stops
    /// [`SHADOW_RAY_REACH`] of the way. `None` when the ends coincide.
    pub fn shadow_ray(&self, a: Vec3, a_ng: Vec3, b: Vec3, b_ng: Vec3) -> Option<Ray> {
        let dir = b - a;
        let from = self.offset(a, a_ng, dir);
        let to = self.offset(b, b_ng, -dir);
        let d = to - from;
        let reach = d.length();
        if !positive(reach) {
            return None;
        }
        Some(Ray::new(from, d / reach, 0.0, reach * SHADOW_RAY_REACH))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    #[test]
    fn hits_carry_pt_conventions() {
        let scene = CpuScene::new(&builtin("cornell-box").unwrap());
        let cam = builtin("cornell-box").unwrap().camera;
        let dir = (cam.look_at - cam.position).normalize();
        let hit = scene.intersect(cam.position, dir).expect("the back wall");
        assert!(hit.ng.dot(dir) < 0.0, "walls face the camera");
        assert_eq!(hit.ns, hit.ng, "no vertex normals in the Cornell box");
        assert!((hit.p - (cam.position + hit.t * dir)).length() < 1e-3);
        // Two points on either side of the back wall do not see each other; two in the
        // room do, even when one lies on a wall.
        let room = cam.position + dir * (hit.t * 0.5);
        assert!(scene.unoccluded(room, Vec3::ZERO, hit.p, hit.ng));
        assert!(!scene.unoccluded(room, Vec3::ZERO, hit.p + dir * 10.0, Vec3::ZERO));
    }
}
