//! One vertex type for both subpaths (pbrt-v4's `Vertex`, SmallVCM's `PathVertex`).

use glam::Vec3;

use super::lights::LightPoint;
use super::mis::SubpathMis;
use super::scene::SurfaceHit;
use crate::bsdf::Frame;

/// What a vertex lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    /// The pinhole: the first vertex of a camera subpath.
    Camera,
    /// A point on a light: the first vertex of a light subpath, or a next-event sample.
    Light,
    /// A surface hit, scattering by its material's BSDF.
    Surface,
}

/// Marks "no triangle" in [`Vertex::triangle`].
pub const NO_TRIANGLE: u32 = u32::MAX;

/// A subpath vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    pub kind: VertexKind,
    pub p: Vec3,
    /// Unit geometric normal (a triangle's front; zero for the pinhole and point lights).
    pub ng: Vec3,
    /// Unit shading normal, on the side of `ng` (equal to it on lights).
    pub ns: Vec3,
    /// The local shading frame about `ns`.
    pub frame: Frame,
    /// Unit direction towards the previous vertex of the subpath (zero on the first).
    pub wo: Vec3,
    /// The material (surfaces) or the light's index in the light table (lights).
    pub material: u32,
    /// The triangle (surfaces, area lights), else [`NO_TRIANGLE`].
    pub triangle: u32,
    /// Emitted radiance (area light) or intensity (point light) of a light vertex.
    pub le: Vec3,
    /// Throughput of the subpath up to and including this vertex: camera subpaths carry
    /// W_e-weighted throughput (1 at the first hit's arrival), light subpaths flux
    /// (1 / position density on the light vertex itself, `Le cos / (p_A p_ω)` after).
    pub beta: Vec3,
    /// Area density of this vertex under its own subpath's sampling (the light's
    /// position density on a light vertex, 1 on the pinhole).
    pub pdf_fwd: f32,
    /// Area density of this vertex under the opposite subpath's sampling from the next
    /// vertex of this subpath; set when the subpath scattered past it (0 otherwise).
    pub pdf_rev: f32,
    /// The subpath left this vertex through a delta lobe; on a light vertex: a point
    /// light (delta position).
    pub delta: bool,
    /// A connection can evaluate this vertex's BSDF (it has a non-delta lobe), or it is
    /// the pinhole or a light.
    pub connectible: bool,
    /// The recursive MIS quantities on arrival at this vertex.
    pub mis: SubpathMis,
}

impl Vertex {
    /// The pinhole.
    pub fn camera(p: Vec3, mis: SubpathMis) -> Self {
        Self {
            kind: VertexKind::Camera,
            p,
            ng: Vec3::ZERO,
            ns: Vec3::ZERO,
            frame: Frame::from_normal(Vec3::Z),
            wo: Vec3::ZERO,
            material: 0,
            triangle: NO_TRIANGLE,
            le: Vec3::ZERO,
            beta: Vec3::ONE,
            pdf_fwd: 1.0,
            pdf_rev: 0.0,
            delta: false,
            connectible: true,
            mis,
        }
    }

    /// A point on a light, chosen with density `point.pdf_area`.
    pub fn light(point: &LightPoint, triangle: u32) -> Self {
        let n = if point.delta { Vec3::ZERO } else { point.n };
        Self {
            kind: VertexKind::Light,
            p: point.p,
            ng: n,
            ns: n,
            frame: Frame::from_normal(if point.delta { Vec3::Z } else { n }),
            wo: Vec3::ZERO,
            material: point.light,
            triangle,
            le: point.radiance,
            beta: Vec3::splat(1.0 / point.pdf_area),
            pdf_fwd: point.pdf_area,
            pdf_rev: 0.0,
            delta: point.delta,
            connectible: true,
            mis: SubpathMis::default(),
        }
    }

    /// A surface hit reached from direction `wo` (towards the previous vertex).
    pub fn surface(hit: &SurfaceHit, wo: Vec3, connectible: bool) -> Self {
        Self {
            kind: VertexKind::Surface,
            p: hit.p,
            ng: hit.ng,
            ns: hit.ns,
            frame: Frame::from_normal(hit.ns),
            wo,
            material: hit.material,
            triangle: hit.triangle,
            le: Vec3::ZERO,
            beta: Vec3::ZERO,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            delta: false,
            connectible,
            mis: SubpathMis::default(),
        }
    }

    pub fn is_surface(&self) -> bool {
        self.kind == VertexKind::Surface
    }

    /// |cos θ| of the unit direction `w` against the geometric normal; 1 where there is
    /// none (a point light, the pinhole).
    pub fn abs_cos(&self, w: Vec3) -> f32 {
        if self.ng == Vec3::ZERO {
            1.0
        } else {
            self.ng.dot(w).abs()
        }
    }

    /// The area density at `next` of a solid-angle density `pdf_dir` from this vertex:
    /// `pdf_dir · |cos θ_next| / d²`.
    pub fn area_density_at(&self, next: &Vertex, pdf_dir: f32) -> f32 {
        let d = next.p - self.p;
        let dist2 = d.length_squared();
        if dist2 <= 0.0 {
            return 0.0;
        }
        pdf_dir * next.abs_cos(d / dist2.sqrt()) / dist2
    }
}
