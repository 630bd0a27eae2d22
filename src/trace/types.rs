//! Ray, hit and triangle records as the GPU sees them (std430). The GLSL side is
//! `glsl/common/geometry.glsl`; `tests/suite/trace_brute_force.rs` proves the two agree.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Marks a miss in [`Hit::triangle`].
pub const MISS: u32 = u32::MAX;

#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct Ray {
    pub origin: [f32; 3],
    pub tmin: f32,
    /// Unit length for every ray the engine makes, so t is a distance.
    pub dir: [f32; 3],
    pub tmax: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Self {
        Self {
            origin: origin.into(),
            tmin,
            dir: dir.into(),
            tmax,
        }
    }

    /// Whether the segment (tmin, tmax) holds no point: tmax <= tmin, or either is NaN.
    /// Such a ray hits nothing (the integrators' "no ray"; see [`super::Tracer`]). GLSL
    /// twin: `ray_is_empty` in glsl/common/geometry.glsl.
    pub fn is_empty(&self) -> bool {
        self.tmax.partial_cmp(&self.tmin) != Some(std::cmp::Ordering::Greater)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct Hit {
    /// Distance along the ray; +inf for a miss.
    pub t: f32,
    /// Index of the triangle in scene order, or [`MISS`].
    pub triangle: u32,
    pub u: f32,
    pub v: f32,
}

impl Hit {
    pub const NONE: Hit = Hit {
        t: f32::INFINITY,
        triangle: MISS,
        u: 0.0,
        v: 0.0,
    };

    pub fn is_hit(&self) -> bool {
        self.triangle != MISS
    }
}

/// A triangle as the tracers read it: its three vertices (w unused). Vertices rather
/// than edges, so that a vertex two triangles share is the same bits in both, which the
/// watertight intersection test ([`super::cpu::intersect_triangle`]) needs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct GpuTriangle {
    pub v0: [f32; 4],
    pub v1: [f32; 4],
    pub v2: [f32; 4],
}

impl GpuTriangle {
    pub fn new(p: [Vec3; 3]) -> Self {
        Self {
            v0: p[0].extend(0.0).into(),
            v1: p[1].extend(0.0).into(),
            v2: p[2].extend(0.0).into(),
        }
    }

    pub fn v0(&self) -> Vec3 {
        Vec3::from_slice(&self.v0[..3])
    }

    pub fn vertices(&self) -> [Vec3; 3] {
        [self.v0, self.v1, self.v2].map(|v| Vec3::from_slice(&v[..3]))
    }

    /// The corners (min, max) of the triangle's axis-aligned box.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let [v0, v1, v2] = self.vertices();
        (v0.min(v1).min(v2), v0.max(v1).max(v2))
    }

    /// The edge from vertex 0 to vertex 1.
    pub fn e1(&self) -> Vec3 {
        Vec3::from_slice(&self.v1[..3]) - self.v0()
    }

    /// The edge from vertex 0 to vertex 2.
    pub fn e2(&self) -> Vec3 {
        Vec3::from_slice(&self.v2[..3]) - self.v0()
    }

    /// Unnormalised geometric normal e1 × e2 (its side follows the vertex winding;
    /// `triangle_normal` in glsl/common/geometry.glsl).
    pub fn normal(&self) -> Vec3 {
        self.e1().cross(self.e2())
    }
}

const _: () = assert!(size_of::<Ray>() == 32);
const _: () = assert!(size_of::<Hit>() == 16);
const _: () = assert!(size_of::<GpuTriangle>() == 48);
