//! Evaluating one technique (s, t) of a camera and a light subpath: its contribution
//! (the path's measurement over the technique's density, CBPT's g_{i,j} / p_{i,j}) and
//! its balance-heuristic weight w_{i,j} from the recursive quantities of
//! [`super::mis`]; CBPT's basic contribution f_{i,j} is their product (§3.1, eq. 2).
//!
//! Every factor follows Veach's formulation with shading normals (1997, §5.3): a
//! camera-side endpoint contributes f(wo, wi) |wi·ns|, a light-side endpoint the adjoint
//! f*(wo, wi) |wi·ns| times the shading-normal correction, the connecting segment 1/d²
//! (the geometric cosines of G are absorbed by the shading ones), and area densities
//! convert solid angle with the geometric cosine at the receiving vertex.

use glam::Vec3;

use super::camera::PinholeCamera;
use super::lights::Lights;
use super::mis;
use super::random::{dims, PathSampler};
use super::scene::CpuScene;
use super::vertex::{Vertex, NO_TRIANGLE};
use super::walk::WalkSettings;
use super::{positive, Counters};
use crate::bsdf::{shading_normal_correction, TransportMode};

/// One evaluated technique.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Light vertices.
    pub s: u32,
    /// Camera vertices (1: light tracing).
    pub t: u32,
    /// The unweighted contribution (for t = 1: to the pixel in `pixel`, before dividing
    /// by the light subpaths of the pass).
    pub value: Vec3,
    /// The balance-heuristic weight.
    pub weight: f32,
    /// Light tracing: the pixel the light vertex projects to.
    pub pixel: Option<u32>,
}

impl Sample {
    pub fn weighted(&self) -> Vec3 {
        self.value * self.weight
    }
}

/// A connection endpoint's BSDF towards the other endpoint: CBPT's shading tuple
/// (f_s, p, p*) of a linking vertex (§3.1), which its GPU kernels compute.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Endpoint {
    /// f |wi·ns| (light subpaths: the adjoint, times the shading-normal correction).
    pub f: Vec3,
    /// Solid-angle density of sampling the direction to the other endpoint.
    pub pdf_fwd: f32,
    /// Solid-angle density of sampling the direction to this vertex's predecessor,
    /// arriving from the other endpoint.
    pub pdf_rev: f32,
}

/// The unit direction from `from` to `to` and their squared distance; `None` when they
/// coincide.
pub fn segment(from: Vec3, to: Vec3) -> Option<(Vec3, f32)> {
    let d = to - from;
    let dist2 = d.length_squared();
    positive(dist2).then(|| (d / dist2.sqrt(), dist2))
}

/// The BSDF of surface vertex `v` towards the unit direction `dir` (`mode`: radiance on
/// camera subpaths, importance on light subpaths).
pub fn endpoint(scene: &CpuScene, v: &Vertex, dir: Vec3, mode: TransportMode) -> Endpoint {
    let bsdf = scene.bsdf(v.material);
    let (wo, wi) = (v.frame.to_local(v.wo), v.frame.to_local(dir));
    let mut f = bsdf.eval(wo, wi, mode) * wi.z.abs();
    if mode == TransportMode::Importance {
        f *= shading_normal_correction(v.wo, dir, v.ns, v.ng, mode);
    }
    Endpoint {
        f,
        pdf_fwd: bsdf.pdf(wo, wi, mode),
        pdf_rev: bsdf.pdf(wi, wo, mode),
    }
}

/// The techniques of one scene, camera and set of counts.
#[derive(Clone, Copy)]
pub struct Connector<'a> {
    pub scene: &'a CpuScene,
    pub camera: &'a PinholeCamera,
    pub settings: &'a WalkSettings,
}

impl<'a> Connector<'a> {
    fn lights(&self) -> Lights<'a> {
        Lights::new(&self.scene.tables.lights)
    }

    fn counts(&self) -> &mis::TechniqueCounts {
        &self.settings.counts
    }

    fn endpoint(&self, v: &Vertex, dir: Vec3, mode: TransportMode) -> Endpoint {
        endpoint(self.scene, v, dir, mode)
    }

    /// s = 0: camera vertex `j` lies on an emitter facing the previous vertex.
    pub fn emitter_hit(&self, camera: &[Vertex], j: usize, c: &mut Counters) -> Option<Sample> {
        let z = &camera[j];
        if !z.is_surface() || self.counts().emitter_hit <= 0.0 {
            return None;
        }
        let le = self.scene.emission(z.material);
        let cos = z.ng.dot(z.wo);
        if le == Vec3::ZERO || cos <= 0.0 {
            return None;
        }
        c.basic_contributions += 1;
        let area = self.scene.triangle_area(z.triangle);
        let pdf_area = self.lights().pdf_area_of_triangle(z.triangle, area);
        let emit_dir = cos * std::f32::consts::FRAC_1_PI;
        let weight =
            mis::emitter_hit_weight(self.counts(), j, &z.mis, pdf_area, pdf_area, emit_dir);
        Some(Sample {
            s: 0,
            t: j as u32 + 1,
            value: z.beta * le,
            weight,
            pixel: None,
        })
    }

    /// s = 1: a fresh light sample connected to camera vertex `j` (next-event
    /// estimation), with its random numbers from the vertex's dimensions.
    pub fn light_sample(
        &self,
        camera: &[Vertex],
        j: usize,
        sampler: &PathSampler,
        c: &mut Counters,
    ) -> Option<Sample> {
        let z = &camera[j];
        if !z.is_surface() || !z.connectible || self.counts().light_sample <= 0.0 {
            return None;
        }
        let u = [
            sampler.get(dims::camera_vertex(j as u32, dims::LIGHT_PICK)),
            sampler.get(dims::camera_vertex(j as u32, dims::LIGHT_POINT)),
            sampler.get(dims::camera_vertex(j as u32, dims::LIGHT_POINT + 1)),
        ];
        let point = self.lights().sample(u)?;
        let light = Vertex::light(&point, NO_TRIANGLE);
        self.connect_light_point(&light, camera, j, c)
    }

    /// s = 1 for a given light vertex (a next-event sample).
    pub fn connect_light_point(
        &self,
        light: &Vertex,
        camera: &[Vertex],
        j: usize,
        c: &mut Counters,
    ) -> Option<Sample> {
        let z = &camera[j];
        let (dir, _) = segment(z.p, light.p)?;
        c.basic_contributions += 1;
        let e = self.endpoint(z, dir, TransportMode::Radiance);
        let sample = self.weigh_light_point(light, camera, j, &e)?;
        self.visible(z, light, c).then_some(sample)
    }

    /// s = 1 from camera vertex `j`'s BSDF towards the light point, `e` (evaluated by
    /// `Connector::endpoint` or by CBPT's kernels): the sample as if unoccluded, `None`
    /// when it carries nothing.
    pub fn weigh_light_point(
        &self,
        light: &Vertex,
        camera: &[Vertex],
        j: usize,
        e: &Endpoint,
    ) -> Option<Sample> {
        let z = &camera[j];
        let (dir, dist2) = segment(z.p, light.p)?;
        let cos_light = light.abs_cos(dir);
        let le = if light.delta || light.ng.dot(-dir) > 0.0 {
            light.le
        } else {
            Vec3::ZERO
        };
        let value = z.beta * e.f * le * (cos_light / (dist2 * light.pdf_fwd));
        if value == Vec3::ZERO {
            return None;
        }
        let emit_dir = if light.delta {
            crate::bsdf::sampling::uniform_sphere_pdf()
        } else {
            cos_light * std::f32::consts::FRAC_1_PI
        };
        let light_rev = if light.delta {
            0.0
        } else {
            e.pdf_fwd * cos_light / dist2
        };
        let camera_fwd = emit_dir * z.abs_cos(dir) / dist2;
        let camera_partial = z
            .mis
            .partial(self.counts().camera_vertex(j, false), e.pdf_rev);
        let weight = mis::light_sample_weight(
            self.counts(),
            light_rev,
            light.pdf_fwd,
            light.pdf_fwd,
            camera_fwd,
            camera_partial,
        );
        Some(Sample {
            s: 1,
            t: j as u32 + 1,
            value,
            weight,
            pixel: None,
        })
    }

    /// s ≥ 2, t ≥ 2: light vertex `i` ≥ 1 connected to camera vertex `j` ≥ 1.
    pub fn connect(
        &self,
        light: &[Vertex],
        i: usize,
        camera: &[Vertex],
        j: usize,
        c: &mut Counters,
    ) -> Option<Sample> {
        let (y, z) = (&light[i], &camera[j]);
        if !y.connectible || !z.connectible || self.counts().connection <= 0.0 {
            return None;
        }
        let (dir, _) = segment(z.p, y.p)?;
        c.basic_contributions += 1;
        let ez = self.endpoint(z, dir, TransportMode::Radiance);
        let ey = self.endpoint(y, -dir, TransportMode::Importance);
        let sample = self.weigh_connection(light, i, camera, j, &ez, &ey)?;
        self.visible(z, y, c).then_some(sample)
    }

    /// s ≥ 2, t ≥ 2 from the two endpoints' BSDFs towards each other, `ez` (camera
    /// vertex `j`, radiance) and `ey` (light vertex `i`, importance), evaluated by
    /// `Connector::endpoint` or by CBPT's kernels: the sample as if unoccluded, `None`
    /// when it carries nothing.
    pub fn weigh_connection(
        &self,
        light: &[Vertex],
        i: usize,
        camera: &[Vertex],
        j: usize,
        ez: &Endpoint,
        ey: &Endpoint,
    ) -> Option<Sample> {
        let (y, z) = (&light[i], &camera[j]);
        let (dir, dist2) = segment(z.p, y.p)?;
        let value = y.beta * ey.f * ez.f * z.beta / dist2;
        if value == Vec3::ZERO {
            return None;
        }
        let counts = self.counts();
        let weight = mis::connection_weight(
            counts,
            ez.pdf_fwd * y.abs_cos(dir) / dist2,
            y.mis.partial(counts.light_vertex(i), ey.pdf_rev),
            ey.pdf_fwd * z.abs_cos(dir) / dist2,
            z.mis.partial(counts.camera_vertex(j, false), ez.pdf_rev),
        );
        Some(Sample {
            s: i as u32 + 1,
            t: j as u32 + 1,
            value,
            weight,
            pixel: None,
        })
    }

    /// t = 1: light vertex `i` connected to the pinhole and splatted to the pixel it
    /// projects to (i = 0: technique (1, 1), the emitter point itself).
    pub fn light_trace(&self, light: &[Vertex], i: usize, c: &mut Counters) -> Option<Sample> {
        let y = &light[i];
        let count = if i == 0 {
            self.counts().light_trace_emitter
        } else {
            self.counts().light_trace
        };
        if !y.connectible || count <= 0.0 || (i == 0 && y.delta) {
            return None;
        }
        let to = self.camera.position() - y.p;
        let dist2 = to.length_squared();
        if !positive(dist2) {
            return None;
        }
        let dir = to / dist2.sqrt();
        let pixel = self.camera.pixel_of(-dir)?;
        c.basic_contributions += 1;
        let cos_cam = self.camera.cos_theta(-dir);
        let camera_area = self.camera.pdf_direction(-dir) * y.abs_cos(dir) / dist2;
        let we = self.camera.importance(-dir);
        let (f, weight) = if i == 0 {
            let le = if y.ng.dot(dir) > 0.0 {
                y.le
            } else {
                Vec3::ZERO
            };
            let w = mis::light_trace_emitter_weight(self.counts(), camera_area, y.pdf_fwd, false);
            (le * y.abs_cos(dir), w)
        } else {
            let e = self.endpoint(y, dir, TransportMode::Importance);
            let partial = y.mis.partial(self.counts().light_vertex(i), e.pdf_rev);
            (
                e.f,
                mis::light_trace_weight(self.counts(), camera_area, partial),
            )
        };
        let value = y.beta * f * (we * cos_cam / dist2);
        if value == Vec3::ZERO {
            return None;
        }
        let pinhole = Vertex::camera(self.camera.position(), Default::default());
        self.visible(y, &pinhole, c).then_some(Sample {
            s: i as u32 + 1,
            t: 1,
            value,
            weight,
            pixel: Some(pixel),
        })
    }

    fn visible(&self, a: &Vertex, b: &Vertex, c: &mut Counters) -> bool {
        c.connections += 1;
        c.rays += 1;
        self.scene.unoccluded(a.p, a.ng, b.p, b.ng)
    }
}
