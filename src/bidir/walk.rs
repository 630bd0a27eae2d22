//! Random walks: the camera subpath of a pixel and a light subpath, as vertex lists with
//! their throughputs, densities and recursive MIS quantities (pbrt-v4's
//! `GenerateCameraSubpath` / `GenerateLightSubpath` / `RandomWalk`).
//!
//! **Depth** is Mitsuba's, as in `pt`: `max_depth` bounds the segments of a complete
//! path (1: emitters seen directly, 2: direct light; negative: unbounded). A camera
//! subpath therefore holds at most max_depth + 1 vertices (the pinhole and max_depth
//! hits, the last of which may lie on an emitter), a light subpath at most max_depth (a
//! light vertex y_i completes a path of i + 1 segments when it is traced to the camera).
//!
//! **Russian roulette** is `pt`'s: after sampling the direction out of vertex i ≥
//! `rr_depth` (the pinhole and the light vertex are vertex 0), the subpath survives with
//! q = min(max(β) · η², 0.95) and β /= q. On a light subpath β is the scattering
//! throughput alone (the product of f |cos| / p since the light; its emitted flux is no
//! measure of how much the path still carries) and η² stays 1: importance transport does
//! not scale by 1/η² across refraction. The survival probability is not part of the MIS
//! densities (see [`super::mis`]).
//!
//! **Shading normals**: a light subpath's throughput takes the adjoint BSDF's correction
//! |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|) (Veach 1997, §5.3; pbrt-v4#13).

use glam::Vec3;

use super::camera::PinholeCamera;
use super::lights::Lights;
use super::mis::{EmissionDensities, SubpathMis, TechniqueCounts};
use super::random::{dims, PathSampler};
use super::scene::CpuScene;
use super::vertex::{Vertex, NO_TRIANGLE};
use super::{positive, Counters};
use crate::bsdf::{shading_normal_correction, TransportMode};

/// What bounds and weights the subpaths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkSettings {
    /// Mitsuba's max_depth (< 0: unbounded).
    pub max_depth: i32,
    /// Russian roulette from this vertex on.
    pub rr_depth: u32,
    pub counts: TechniqueCounts,
}

impl WalkSettings {
    /// Most vertices of a camera subpath, the pinhole included.
    pub fn camera_vertices(&self) -> usize {
        if self.max_depth < 0 {
            usize::MAX
        } else {
            self.max_depth as usize + 1
        }
    }

    /// Most vertices of a light subpath, the light vertex included.
    pub fn light_vertices(&self) -> usize {
        if self.max_depth < 0 {
            usize::MAX
        } else {
            self.max_depth as usize
        }
    }

    /// Whether a complete path of `segments` segments is within `max_depth`.
    pub fn allows(&self, segments: usize) -> bool {
        self.max_depth < 0 || segments <= self.max_depth as usize
    }
}

/// Where on the film a camera subpath starts: a pixel and a point in it, in [0, 1)².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmPoint {
    pub pixel: u32,
    pub jitter: [f32; 2],
}

/// Traces the camera subpath of `pixel` into `path` (cleared first), jittered within the
/// pixel by the sampler's [`dims::CAMERA_JITTER`] dimensions.
pub fn camera_subpath(
    scene: &CpuScene,
    camera: &PinholeCamera,
    settings: &WalkSettings,
    sampler: &PathSampler,
    pixel: u32,
    path: &mut Vec<Vertex>,
    counters: &mut Counters,
) {
    let jitter = [
        sampler.get(dims::CAMERA_JITTER),
        sampler.get(dims::CAMERA_JITTER + 1),
    ];
    let film = FilmPoint { pixel, jitter };
    camera_subpath_at(scene, camera, settings, sampler, film, path, counters);
}

/// Traces the camera subpath through `film` into `path` (cleared first): for callers
/// that choose film positions themselves (CBPT's stratified image positions); the
/// sampler's jitter dimensions are then unused.
pub fn camera_subpath_at(
    scene: &CpuScene,
    camera: &PinholeCamera,
    settings: &WalkSettings,
    sampler: &PathSampler,
    film: FilmPoint,
    path: &mut Vec<Vertex>,
    counters: &mut Counters,
) {
    path.clear();
    if settings.camera_vertices() < 2 {
        return;
    }
    let dir = camera.ray_direction(film.pixel, film.jitter);
    let pdf_dir = camera.pdf_direction(dir);
    path.push(Vertex::camera(
        camera.position(),
        SubpathMis::camera(pdf_dir),
    ));
    counters.camera_paths += 1;
    let walk = Walk {
        scene,
        settings,
        sampler,
        mode: TransportMode::Radiance,
        limit: settings.camera_vertices(),
    };
    let start = MisStart::Ready(SubpathMis::camera(pdf_dir));
    walk.extend(
        path,
        start,
        camera.position(),
        dir,
        pdf_dir,
        Vec3::ONE,
        counters,
    );
}

/// Traces a light subpath into `path` (cleared first; empty when the scene has no
/// lights).
pub fn light_subpath(
    scene: &CpuScene,
    settings: &WalkSettings,
    sampler: &PathSampler,
    path: &mut Vec<Vertex>,
    counters: &mut Counters,
) {
    path.clear();
    let lights = Lights::new(&scene.tables.lights);
    if lights.is_empty() || settings.light_vertices() < 1 {
        return;
    }
    let u_point = [
        sampler.get(dims::emission(dims::EMIT_PICK)),
        sampler.get(dims::emission(dims::EMIT_POINT)),
        sampler.get(dims::emission(dims::EMIT_POINT + 1)),
    ];
    let u_dir = [
        sampler.get(dims::emission(dims::EMIT_DIRECTION)),
        sampler.get(dims::emission(dims::EMIT_DIRECTION + 1)),
    ];
    let Some(e) = lights.sample_emission(u_point, u_dir) else {
        return;
    };
    counters.light_paths += 1;
    let triangle = if e.point.delta {
        NO_TRIANGLE
    } else {
        scene.tables.lights.lights[e.point.light as usize].e2_tri[3].to_bits()
    };
    let light = Vertex::light(&e.point, triangle);
    path.push(light);
    let start = MisStart::Emission(EmissionDensities {
        direct: e.point.pdf_area,
        emit: e.point.pdf_area,
        direction: e.pdf_dir,
        cos: 1.0, // from the vertices, on arrival
        delta_position: e.point.delta,
    });
    let walk = Walk {
        scene,
        settings,
        sampler,
        mode: TransportMode::Importance,
        limit: settings.light_vertices(),
    };
    let origin = scene.offset(light.p, light.ng, e.dir);
    walk.extend(path, start, origin, e.dir, e.pdf_dir, e.weight, counters);
}

/// How a walk's MIS quantities start.
enum MisStart {
    Ready(SubpathMis),
    /// A light subpath's, once the cosine at the light towards the first hit is known.
    Emission(EmissionDensities),
}

/// A scattering event whose MIS update waits for the next vertex: its cosine is taken
/// between the two vertices' positions, as every connection takes it, not along the ray
/// (which leaves from an offset origin), so that the recursive weights and the densities
/// a connection evaluates afresh describe the same path.
struct PendingScatter {
    count: f32,
    pdf_fwd: f32,
    pdf_rev: f32,
    delta: bool,
}

/// One subpath's random walk past its first vertex.
struct Walk<'a> {
    scene: &'a CpuScene,
    settings: &'a WalkSettings,
    sampler: &'a PathSampler,
    mode: TransportMode,
    limit: usize,
}

impl Walk<'_> {
    /// The dimension `offset` of vertex `i`.
    fn dim(&self, i: usize, offset: u32) -> u32 {
        match self.mode {
            TransportMode::Radiance => dims::camera_vertex(i as u32, offset),
            TransportMode::Importance => dims::light_vertex(i as u32, offset),
        }
    }

    /// The count of vertex `i`'s `d_vcm` term.
    fn count(&self, i: usize) -> f32 {
        match self.mode {
            TransportMode::Radiance => self.settings.counts.camera_vertex(i, false),
            TransportMode::Importance => self.settings.counts.light_vertex(i),
        }
    }

    /// Extends `path` (holding its first vertex) from `origin` along `dir`, sampled with
    /// solid-angle density `pdf_dir`, carrying throughput `beta`.
    #[allow(clippy::too_many_arguments)]
    fn extend(
        &self,
        path: &mut Vec<Vertex>,
        start: MisStart,
        mut origin: Vec3,
        mut dir: Vec3,
        mut pdf_dir: f32,
        mut beta: Vec3,
        counters: &mut Counters,
    ) {
        let (mut mis, mut emission) = match start {
            MisStart::Ready(m) => (m, None),
            MisStart::Emission(e) => (SubpathMis::default(), Some(e)),
        };
        let mut pending: Option<PendingScatter> = None;
        // Roulette's measure of what the subpath still carries: β of a camera subpath
        // (as in pt, survival divisions included), the scattering part of a light
        // subpath's, and the product of η² (camera only).
        let mut carried = Vec3::ONE;
        let mut eta2 = 1.0f32;
        while path.len() < self.limit {
            counters.rays += 1;
            let Some(hit) = self.scene.intersect(origin, dir) else {
                return;
            };
            let prev = &path[path.len() - 1];
            let to_prev = prev.p - hit.p;
            let dist2 = to_prev.length_squared();
            if !positive(dist2) {
                return;
            }
            let wo = to_prev / dist2.sqrt();
            let mut v = Vertex::surface(&hit, wo, self.scene.connectible(hit.material));
            let (cos_in, cos_out) = (v.abs_cos(wo), prev.abs_cos(-wo));
            if !positive(cos_in) {
                return;
            }
            if let Some(mut e) = emission.take() {
                e.cos = cos_out;
                mis = SubpathMis::light(&self.settings.counts, &e);
            }
            if let Some(p) = pending.take() {
                mis.scatter(p.count, cos_out, p.pdf_fwd, p.pdf_rev, p.delta);
            }
            mis.arrive(dist2, cos_in);
            v.mis = mis;
            v.beta = beta;
            v.pdf_fwd = pdf_dir * cos_in / dist2;
            path.push(v);
            counters.vertices += 1;
            if path.len() >= self.limit {
                return;
            }
            let Some(next) = self.scatter(path, &mut carried, &mut eta2) else {
                return;
            };
            beta = next.beta;
            dir = next.dir;
            pdf_dir = next.scatter.pdf_fwd;
            pending = Some(next.scatter);
            let v = path.last().expect("pushed above");
            origin = self.scene.offset(v.p, v.ng, dir);
        }
    }

    /// Samples the direction out of the last vertex, plays Russian roulette and sets the
    /// previous vertex's reverse density. `None` ends the subpath.
    fn scatter(&self, path: &mut [Vertex], carried: &mut Vec3, eta2: &mut f32) -> Option<Next> {
        let i = path.len() - 1;
        let v = path[i];
        let bsdf = self.scene.bsdf(v.material);
        let wo = v.frame.to_local(v.wo);
        let s = bsdf.sample(wo, self.sampler.get3(self.dim(i, dims::BSDF)), self.mode)?;
        if !positive(s.pdf) {
            return None;
        }
        let wi = v.frame.to_world(s.wi).normalize();
        let mut factor = s.f * (s.wi.z.abs() / s.pdf);
        if self.mode == TransportMode::Importance {
            factor *= shading_normal_correction(v.wo, wi, v.ns, v.ng, self.mode);
        } else {
            *eta2 *= s.eta * s.eta;
        }
        *carried *= factor;
        let mut beta = v.beta * factor;
        if !positive(beta.max_element()) {
            return None;
        }
        if i as u32 >= self.settings.rr_depth {
            let q = (carried.max_element() * *eta2).min(0.95);
            if self.sampler.get(self.dim(i, dims::ROULETTE)) >= q {
                return None;
            }
            beta /= q;
            *carried /= q;
        }
        let delta = s.flags.is_specular();
        // Delta lobes sample the same discrete probability both ways (see super::mis).
        let pdf_rev = if delta {
            s.pdf
        } else {
            bsdf.pdf(s.wi, wo, self.mode)
        };
        let prev = path[i - 1];
        path[i - 1].pdf_rev = v.area_density_at(&prev, pdf_rev);
        path[i].delta = delta;
        Some(Next {
            beta,
            dir: wi,
            scatter: PendingScatter {
                count: self.count(i),
                pdf_fwd: s.pdf,
                pdf_rev,
                delta,
            },
        })
    }
}

/// Where a walk goes after scattering.
struct Next {
    beta: Vec3,
    dir: Vec3,
    scatter: PendingScatter,
}
