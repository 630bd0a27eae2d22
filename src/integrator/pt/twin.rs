//! CPU twins of `pt`'s kernels (`glsl/integrator/pt/*.comp`), for the tests that compare
//! them (`tests/suite/pt_kernels.rs`):
//! - [`PathTwin::radiance`]: one sample of one pixel as `generate`, `shade` and
//!   `nee_accumulate` compute it bounce after bounce, with the same random numbers, on
//!   the CPU BVH ([`CpuScene`]) where the kernels use a [`crate::trace::Tracer`];
//! - [`nee_accumulate`] and [`finish`]: those kernels alone, on their records.
//!
//! The twin follows `shade.comp` statement for statement, in its order of additions, so
//! that a sample differs from the kernel's only by float rounding, until rounding tips a
//! decision (a hit at a triangle's edge, a Russian roulette draw at its threshold) and
//! the two paths part.

use glam::Vec3;

use super::gpu::{PathState, LIGHT_POINT};
use super::{PtOptions, Strategy};
use crate::bidir::positive;
use crate::bidir::random::{fold_seed, random01};
use crate::bidir::scene::SurfaceHit;
use crate::bidir::{CpuScene, PinholeCamera};
use crate::bsdf::{BsdfParams, Frame, TransportMode};
use crate::film::compensated;
use crate::scene::CameraFrame;
use crate::trace::{Hit, Ray, MISS};

/// Random-number dimensions of `pt.glsl`: 0 and 1 jitter the pixel, then
/// [`DIMS_PER_BOUNCE`] per bounce.
const DIMS_PER_BOUNCE: u32 = 8;
const DIM_LIGHT_SELECT: u32 = 0;
const DIM_LIGHT_U: u32 = 1;
const DIM_LIGHT_V: u32 = 2;
const DIM_BSDF_C: u32 = 3;
const DIM_BSDF_U: u32 = 4;
const DIM_BSDF_V: u32 = 5;
const DIM_RR: u32 = 6;

/// `pt_dim` of pt.glsl.
fn dim(bounce: u32, k: u32) -> u32 {
    2 + bounce * DIMS_PER_BOUNCE + k
}

/// `power_heuristic` of shade.comp (0 where both densities are 0).
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// What a path carries from one bounce to the next (`PathState`).
struct State {
    beta: Vec3,
    /// Product of η² of the refractions so far (Russian roulette uses β·η²).
    eta2: f32,
    radiance: Vec3,
    /// Solid-angle density of the BSDF sample that led here.
    prev_pdf: f32,
    /// The previous event was a delta lobe (or the camera).
    prev_delta: bool,
    depth: u32,
}

/// Which estimators count (`PT_FLAG_NEE`, `PT_FLAG_BSDF`; both = MIS).
#[derive(Clone, Copy)]
struct Flags {
    nee: bool,
    bsdf: bool,
}

/// The pixel and sample a path belongs to, and the integrator's seed: its random numbers.
#[derive(Clone, Copy)]
struct Draws {
    pixel: u32,
    sample: u32,
    seed: u32,
}

impl Draws {
    fn get(self, dimension: u32) -> f32 {
        random01(self.pixel, self.sample, dimension, self.seed)
    }
}

/// What shading at a hit works with: the hit, its shading frame and BSDF, the direction
/// back along the path in that frame, and the path's random numbers at this bounce.
struct Shading<'s> {
    hit: &'s SurfaceHit,
    frame: Frame,
    bsdf: &'s BsdfParams,
    wo: Vec3,
    bounce: u32,
    draws: Draws,
}

impl Shading<'_> {
    fn draw(&self, k: u32) -> f32 {
        self.draws.get(dim(self.bounce, k))
    }
}

/// A shadow ray and the contribution it carries if it arrives.
struct NextEvent {
    ray: Ray,
    contribution: Vec3,
}

/// `pt` on the CPU, one sample at a time.
pub struct PathTwin<'a> {
    scene: &'a CpuScene,
    camera: PinholeCamera,
    options: PtOptions,
    seed: u32,
}

impl<'a> PathTwin<'a> {
    pub fn new(scene: &'a CpuScene, camera: &CameraFrame, options: &PtOptions) -> Self {
        Self {
            scene,
            camera: PinholeCamera::new(camera),
            options: *options,
            seed: fold_seed(options.seed),
        }
    }

    /// Sample `sample` of `pixel`: the radiance `finish` adds to the film, and the
    /// path's depth (Mitsuba's: vertices after the camera) when it ended.
    pub fn radiance(&self, pixel: u32, sample: u32) -> (Vec3, u32) {
        let draws = Draws {
            pixel,
            sample,
            seed: self.seed,
        };
        // generate.comp
        let mut origin = self.camera.position();
        let mut dir = self
            .camera
            .ray_direction(pixel, [draws.get(0), draws.get(1)]);
        let mut s = State {
            beta: Vec3::ONE,
            eta2: 1.0,
            radiance: Vec3::ZERO,
            prev_pdf: 0.0,
            prev_delta: true,
            depth: 0,
        };
        for bounce in 0.. {
            let Some(hit) = self.scene.intersect(origin, dir) else {
                break; // no environment light
            };
            match self.shade(&mut s, &hit, dir, bounce, draws) {
                Some(next) => (origin, dir) = next,
                None => break,
            }
        }
        (s.radiance, s.depth)
    }

    /// `shade.comp` at `hit`, then `nee_accumulate.comp` for its shadow ray: the next
    /// ray, or `None` where the path ends.
    fn shade(
        &self,
        s: &mut State,
        hit: &SurfaceHit,
        dir: Vec3,
        bounce: u32,
        draws: Draws,
    ) -> Option<(Vec3, Vec3)> {
        let flags = self.flags();
        if let Some((le, w)) = self.emission(s, hit, dir) {
            s.radiance += s.beta * le * w;
        }
        let next = self.options.max_depth < 0 || s.depth as i32 + 1 < self.options.max_depth;
        if !next {
            return None;
        }
        let material = &self.scene.tables.materials[hit.material as usize];
        let frame = Frame::from_normal(hit.ns);
        let at = Shading {
            hit,
            frame,
            bsdf: self.scene.bsdf(hit.material),
            wo: frame.to_local(-dir),
            bounce,
            draws,
        };
        let lights = &self.scene.tables.lights;
        if flags.nee && !lights.lights.is_empty() && material.all_delta == 0 {
            let event = self.next_event(s, &at);
            if let Some(e) = event.filter(|e| !self.scene.bvh.occluded(&e.ray)) {
                s.radiance += e.contribution;
            }
        }
        self.bsdf_step(s, &at)
    }

    /// Which estimators count: next-event estimation, BSDF sampling, both (MIS).
    fn flags(&self) -> Flags {
        let (nee, bsdf) = match self.options.strategy {
            Strategy::Mis => (true, true),
            Strategy::Nee => (true, false),
            Strategy::Bsdf => (false, true),
        };
        Flags { nee, bsdf }
    }

    /// Step 1 of shade.comp: the radiance emitted towards the path at `hit` (one-sided:
    /// the geometric normal's side) and its MIS weight against light sampling; `None`
    /// where it emits none. (Conditions are written as the kernel's, so that NaN takes
    /// the same branch.)
    fn emission(&self, s: &State, hit: &SurfaceHit, dir: Vec3) -> Option<(Vec3, f32)> {
        let le = self.scene.emission(hit.material);
        let cos_l = -hit.ng.dot(dir);
        let seen = self.options.max_depth != 0;
        if !(seen && positive(le.x + le.y + le.z) && positive(cos_l)) {
            return None;
        }
        let flags = self.flags();
        let mut w = 1.0;
        if !s.prev_delta {
            if !flags.bsdf {
                w = 0.0; // NEE alone: emitters count only through light sampling
            } else if flags.nee {
                let area = self.scene.triangle_area(hit.triangle);
                let pmf = self.scene.tables.lights.tri_pmf[hit.triangle as usize];
                let pdf_light = pmf * hit.t * hit.t / (area * cos_l);
                w = power_heuristic(s.prev_pdf, pdf_light);
            }
        }
        Some((le, w))
    }

    /// Step 2 of shade.comp: a light chosen by power, a point on it, and the shadow
    /// ray with its unoccluded contribution; `None` where it contributes nothing.
    fn next_event(&self, s: &State, at: &Shading) -> Option<NextEvent> {
        let table = &self.scene.tables.lights;
        let u = at.draw(DIM_LIGHT_SELECT);
        // `pick_light`: the first light whose cumulative probability exceeds u.
        let index = table
            .cdf
            .partition_point(|&c| c <= u)
            .min(table.cdf.len() - 1);
        let light = &table.lights[index];
        let (u1, u2) = (at.draw(DIM_LIGHT_U), at.draw(DIM_LIGHT_V));
        let pmf = light.emission_pmf[3];
        let p0 = Vec3::from_slice(&light.p0_type[..3]);
        let emitted = Vec3::from_slice(&light.emission_pmf[..3]);
        let x = at.hit.p;
        let delta_light = light.p0_type[3].to_bits() == LIGHT_POINT;
        let (target, le, pdf_light) = if delta_light {
            let dist = (p0 - x).length();
            if !positive(dist) {
                return None;
            }
            (p0, emitted / (dist * dist), pmf)
        } else {
            let e1 = Vec3::from_slice(&light.e1_area[..3]);
            let e2 = Vec3::from_slice(&light.e2_tri[..3]);
            let su = u1.sqrt();
            let target = p0 + (1.0 - su) * e1 + (u2 * su) * e2;
            let to = target - x;
            let dist = to.length();
            let nl = e1.cross(e2).normalize();
            let cl = if dist > 0.0 { -nl.dot(to) / dist } else { 0.0 };
            if !positive(cl) {
                return None;
            }
            (target, emitted, pmf * dist * dist / (light.e1_area[3] * cl))
        };
        if !positive(pdf_light) {
            return None;
        }
        let to = target - x;
        let wi_world = to / to.length();
        let wi = at.frame.to_local(wi_world);
        let f = at.bsdf.eval(at.wo, wi, TransportMode::Radiance) * wi.z.abs();
        if !positive(f.x + f.y + f.z) {
            return None;
        }
        let flags = self.flags();
        let mut w = 1.0;
        if !delta_light && flags.nee && flags.bsdf {
            w = power_heuristic(pdf_light, at.bsdf.pdf(at.wo, wi, TransportMode::Radiance));
        }
        let contribution = s.beta * f * le * (w / pdf_light);
        let origin = self.scene.offset(x, at.hit.ng, wi_world);
        let reach = (target - origin).length();
        let ray = Ray::new(origin, (target - origin) / reach, 0.0, reach * (1.0 - 1e-4));
        Some(NextEvent { ray, contribution })
    }

    /// Steps 3 and 4 of shade.comp: BSDF sampling and Russian roulette; the next ray
    /// where the path lives on.
    fn bsdf_step(&self, s: &mut State, at: &Shading) -> Option<(Vec3, Vec3)> {
        let u = [DIM_BSDF_C, DIM_BSDF_U, DIM_BSDF_V].map(|k| at.draw(k));
        let sample = at.bsdf.sample(at.wo, u, TransportMode::Radiance)?;
        if !positive(sample.pdf) {
            return None;
        }
        s.depth += 1;
        s.beta *= sample.f * (sample.wi.z.abs() / sample.pdf);
        s.eta2 *= sample.eta * sample.eta;
        s.prev_pdf = sample.pdf;
        s.prev_delta = sample.flags.is_specular();
        let wi_world = at.frame.to_world(sample.wi).normalize();
        let beta_max = s.beta.max_element();
        let mut live = beta_max > 0.0;
        if live && s.depth >= self.options.rr_depth {
            let q = (beta_max * s.eta2).min(0.95);
            if at.draw(DIM_RR) < q {
                s.beta /= q;
            } else {
                live = false;
            }
        }
        live.then(|| (self.scene.offset(at.hit.p, at.hit.ng, wi_world), wi_world))
    }
}

/// `nee_accumulate.comp`: the next-event contribution of live path `live_ids[i]` joins
/// its radiance where its shadow ray arrived (`shadow_hits[i]` a miss) and it has one
/// (`nee[i].w` ≠ 0).
pub fn nee_accumulate(
    live_ids: &[u32],
    shadow_hits: &[Hit],
    nee: &[[f32; 4]],
    paths: &mut [PathState],
) {
    for ((&p, hit), c) in live_ids.iter().zip(shadow_hits).zip(nee) {
        if c[3] == 0.0 || hit.triangle != MISS {
            continue;
        }
        let radiance = &mut paths[p as usize].radiance;
        for k in 0..3 {
            radiance[k] += c[k];
        }
    }
}

/// `finish.comp`: path p of a chunk of `paths.len()` paths over the n pixels of the
/// films is a sample of pixel p mod n; each pixel adds its samples in order to Σ L (w
/// counts them) and Σ (s L)², s = `brightness_scale`. Both films hold n sums, then their
/// remainders ([`compensated`]). Returns how many samples were dropped as non-finite
/// (added as 0).
pub fn finish(
    paths: &[PathState],
    accum: &mut [[f32; 4]],
    accum2: &mut [[f32; 4]],
    brightness_scale: f32,
) -> u32 {
    let pixels = accum.len() / 2;
    let mut dropped = 0;
    for (p, path) in paths.iter().enumerate() {
        let mut l = Vec3::from_slice(&path.radiance[..3]);
        if !l.is_finite() {
            l = Vec3::ZERO;
            dropped += 1;
        }
        let scaled = l * brightness_scale;
        let squared = scaled * scaled;
        compensated::add_to_film(accum, p % pixels, [l.x, l.y, l.z, 1.0]);
        compensated::add_to_film(accum2, p % pixels, squared.extend(0.0).into());
    }
    dropped
}
