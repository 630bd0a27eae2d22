//! The ray workloads of the PDACRT paper as integrators: `primary`, `ao`, `shadow`,
//! `reflection` and `path`, one camera sample per pixel per pass.
//!
//! Stages per chunk (each a named dispatch): `camera_rays` → trace → `shade_primary`, or
//! for AO: → `ao_rays` → trace (occlusion) → `shade_ao`, and likewise for the others.

use std::sync::Arc;

use super::frame::write_ranges;
use super::gpu_types::{FrameParams, GpuMaterial};
use super::{
    check_film_size, Integrator, IntegratorError, IntegratorKind, IntegratorStats, SceneFrame,
};
use crate::film::{DeviceFilm, FilmSums};
use crate::scene::{Aabb, CameraFrame};
use crate::shaders;
use crate::trace::{GpuTriangle, Hit, Query, Ray, Tracer};
use crate::vk::{
    self, Buffer, BufferSlice, ComputePipeline, Gpu, MemoryKind, Recorder, StreamKind,
    TimelinePoint,
};

const WORKGROUP: u32 = 64;

/// Scene data the shading kernels read.
pub struct EyeInputs<'a> {
    pub triangles: &'a [GpuTriangle],
    pub triangle_material: &'a [u32],
    pub materials: &'a [GpuMaterial],
    pub camera: CameraFrame,
    /// The scene's bounds: the AO radius is a fraction of their radius, and rays leave
    /// surfaces [`Aabb::ray_epsilon`] off them.
    pub bounds: Aabb,
    /// The shadow integrator's point light: position and intensity (W/sr).
    pub light: glam::Vec4,
}

#[derive(Clone, Copy, Debug)]
pub struct EyeOptions {
    pub integrator: IntegratorKind,
    /// Samples per pixel the render will take: one sample goes through the pixel centre,
    /// more are jittered uniformly within the pixel.
    pub spp: u32,
    pub seed: u64,
    pub ao_rays: u32,
    /// AO rays reach this fraction of the scene radius.
    pub ao_radius_fraction: f32,
    /// Upper bound on rays per chunk (bounds memory).
    pub max_rays_per_chunk: u32,
}

impl Default for EyeOptions {
    fn default() -> Self {
        Self {
            integrator: IntegratorKind::Primary,
            spp: 1,
            seed: 0,
            ao_rays: 8,
            ao_radius_fraction: 0.25,
            max_rays_per_chunk: 1 << 20,
        }
    }
}

struct Pipelines {
    camera_rays: ComputePipeline,
    shade_primary: ComputePipeline,
    ao_rays: ComputePipeline,
    shade_ao: ComputePipeline,
    shadow_rays: ComputePipeline,
    shade_shadow: ComputePipeline,
    reflect_rays: ComputePipeline,
    path_bounce: ComputePipeline,
}

impl Pipelines {
    fn new(gpu: &Gpu) -> vk::Result<Self> {
        let make = |kernel, bindings| {
            vk::compute_pipeline(
                gpu,
                kernel,
                bindings,
                size_of::<FrameParams>() as u32,
                &[WORKGROUP],
            )
        };
        Ok(Self {
            camera_rays: make(shaders::INTEGRATOR_CAMERA_RAYS, 1)?,
            shade_primary: make(shaders::INTEGRATOR_SHADE_PRIMARY, 6)?,
            ao_rays: make(shaders::INTEGRATOR_AO_RAYS, 4)?,
            shade_ao: make(shaders::INTEGRATOR_SHADE_AO, 3)?,
            shadow_rays: make(shaders::INTEGRATOR_SHADOW_RAYS, 7)?,
            shade_shadow: make(shaders::INTEGRATOR_SHADE_SHADOW, 3)?,
            reflect_rays: make(shaders::INTEGRATOR_REFLECT_RAYS, 4)?,
            path_bounce: make(shaders::INTEGRATOR_PATH_BOUNCE, 7)?,
        })
    }
}

/// One set of ray and hit buffers for a chunk: the camera rays, the secondary rays
/// (`per_pixel` for each camera ray) and two vec4 of per-pixel state (the shadow
/// integrator's pending contribution, the path integrator's throughput).
struct RaySlot {
    rays: Buffer,
    hits: Buffer,
    secondary_rays: Buffer,
    secondary_hits: Buffer,
    state: Buffer,
}

impl RaySlot {
    fn new(gpu: &Gpu, index: usize, chunk: u64, per_pixel: u64) -> vk::Result<Self> {
        let ray = size_of::<Ray>() as u64;
        let hit = size_of::<Hit>() as u64;
        let buffer = |name: &str, bytes| {
            gpu.create_buffer(&format!("{name}-{index}"), bytes, MemoryKind::Device)
        };
        Ok(Self {
            rays: buffer("rays", chunk * ray)?,
            hits: buffer("hits", chunk * hit)?,
            secondary_rays: buffer("secondary-rays", chunk * per_pixel * ray)?,
            secondary_hits: buffer("secondary-hits", chunk * per_pixel * hit)?,
            state: buffer("pixel-state", chunk * 32)?,
        })
    }
}

/// The ray workloads as an [`Integrator`]: one camera sample per pixel per pass,
/// processed in chunks of pixels small enough that every ray buffer fits one storage
/// binding. Two chunks are in flight at most: the host waits only to reuse a chunk's
/// buffers. The film is the GPU's per-pixel sum (no second moments).
pub struct EyeIntegrator {
    gpu: Gpu,
    tracer: Box<dyn Tracer>,
    kind: IntegratorKind,
    pipelines: Pipelines,
    triangles: Buffer,
    triangle_material: Buffer,
    materials: Buffer,
    /// Per pixel Σ L (rgb) and samples (w), then their remainders
    /// ([`compensated`](crate::film::compensated)): the film, shared with previews.
    accum: Arc<Buffer>,
    slots: [RaySlot; 2],
    frame: FrameParams,
    ao_radius_fraction: f32,
    chunk: u32,
    passes: u32,
    rays_traced: u64,
}

/// Sets what `frame` takes from the camera and the scene's extent and light.
fn set_scene_params(
    frame: &mut FrameParams,
    camera: &CameraFrame,
    bounds: &Aabb,
    light: glam::Vec4,
    ao_radius_fraction: f32,
) {
    let posed = FrameParams::new(camera);
    (frame.origin, frame.forward, frame.right, frame.up) =
        (posed.origin, posed.forward, posed.right, posed.up);
    frame.ao_radius = ao_radius_fraction * bounds.radius();
    frame.ray_epsilon = bounds.ray_epsilon([camera.origin]);
    frame.light = light.into();
}

impl EyeIntegrator {
    pub fn new(
        gpu: &Gpu,
        tracer: Box<dyn Tracer>,
        inputs: &EyeInputs<'_>,
        options: &EyeOptions,
    ) -> vk::Result<Self> {
        let kind = options.integrator;
        let ao_rays = options.ao_rays.max(1);
        let per_pixel = match kind {
            IntegratorKind::Ao => ao_rays,
            IntegratorKind::Shadow | IntegratorKind::Reflection => 1,
            IntegratorKind::Primary | IntegratorKind::Path => 0,
            other => {
                return Err(vk::VkError::Usage(format!(
                    "'{other}' is not a ray-workload integrator"
                )))
            }
        };
        let pixels = inputs.camera.width as usize * inputs.camera.height as usize;
        let chunk = (options.max_rays_per_chunk / (1 + per_pixel)).clamp(1, pixels.max(1) as u32);
        let mut frame = FrameParams::new(&inputs.camera);
        frame.seed = options.seed as u32 ^ (options.seed >> 32) as u32;
        frame.jitter = (options.spp > 1) as u32;
        frame.ao_rays = ao_rays;
        set_scene_params(
            &mut frame,
            &inputs.camera,
            &inputs.bounds,
            inputs.light,
            options.ao_radius_fraction,
        );
        Ok(Self {
            gpu: gpu.clone(),
            tracer,
            kind,
            pipelines: Pipelines::new(gpu)?,
            triangles: gpu.upload("shade-triangles", inputs.triangles)?,
            triangle_material: gpu.upload("triangle-material", inputs.triangle_material)?,
            materials: gpu.upload("materials", inputs.materials)?,
            // Sums and their remainders (film_sum.glsl).
            accum: Arc::new(gpu.zeroed::<[f32; 4]>("accum", 2 * pixels)?),
            slots: [
                RaySlot::new(gpu, 0, chunk as u64, per_pixel as u64)?,
                RaySlot::new(gpu, 1, chunk as u64, per_pixel as u64)?,
            ],
            frame,
            ao_radius_fraction: options.ao_radius_fraction,
            chunk,
            passes: 0,
            rays_traced: 0,
        })
    }

    fn pixels(&self) -> usize {
        self.frame.width as usize * self.frame.height as usize
    }

    /// Records and submits one chunk of one sample; returns the point that marks it
    /// shaded.
    fn render_chunk(&mut self, slot: usize, count: u32) -> vk::Result<TimelinePoint> {
        let gpu = &self.gpu;
        let slot = &self.slots[slot];
        let n = count as u64;
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &self.pipelines.camera_rays,
            &[(&slot.rays).into()],
            &self.frame,
            n,
        )?;
        let generated = rec.submit(&[])?;
        let tracer = self.tracer.as_mut();
        let traced = tracer.trace(
            &slot.rays,
            &slot.hits,
            count,
            Query::ClosestHit,
            &[&generated],
        )?;
        let rec = gpu.recorder(StreamKind::Main)?;
        let stage = Stage {
            gpu,
            pipelines: &self.pipelines,
            slot,
            triangles: &self.triangles,
            triangle_material: &self.triangle_material,
            materials: &self.materials,
            accum: &self.accum,
            count,
        };
        let frame = &mut self.frame;
        let (done, secondary) = match self.kind {
            IntegratorKind::Ao => stage.ambient_occlusion(rec, frame, &traced, tracer)?,
            IntegratorKind::Shadow => stage.shadow(rec, frame, &traced, tracer)?,
            IntegratorKind::Reflection => stage.reflection(rec, frame, &traced, tracer)?,
            IntegratorKind::Path => stage.path(rec, frame, traced, tracer)?,
            _ => (stage.shade_primary(rec, frame, &traced)?, 0),
        };
        self.rays_traced += n + secondary;
        Ok(done)
    }
}

impl Integrator for EyeIntegrator {
    fn name(&self) -> &'static str {
        self.kind.name()
    }

    fn render_passes(&mut self, first: u32, count: u32) -> Result<(), IntegratorError> {
        let pixels = self.pixels();
        let mut in_flight: [Option<TimelinePoint>; 2] = [None, None];
        let mut step = 0usize;
        for sample in first..first + count {
            self.frame.sample_index = sample;
            for offset in (0..pixels).step_by(self.chunk as usize) {
                let n = self.chunk.min((pixels - offset) as u32);
                self.frame.pixel_offset = offset as u32;
                self.frame.pixel_count = n;
                if let Some(previous) = in_flight[step % 2].take() {
                    self.gpu.wait(&previous)?;
                }
                in_flight[step % 2] = Some(self.render_chunk(step % 2, n)?);
                step += 1;
            }
            self.passes += 1;
        }
        self.gpu.wait_idle()?;
        Ok(())
    }

    fn sums(&mut self) -> Result<FilmSums, IntegratorError> {
        let sum = self.accum.read::<[f32; 4]>()?;
        let (w, h) = (self.frame.width, self.frame.height);
        Ok(FilmSums::from_gpu(w, h, self.passes, 1, &sum, None, 1.0))
    }

    fn restore(&mut self, sums: &FilmSums) -> Result<(), IntegratorError> {
        check_film_size(sums, self.frame.width, self.frame.height, 1)?;
        self.accum.write(&sums.to_gpu(1.0).0)?;
        self.passes = sums.passes;
        Ok(())
    }

    fn stats(&self) -> IntegratorStats {
        IntegratorStats {
            rays_traced: self.rays_traced,
            ..Default::default()
        }
    }

    /// The triangles (tracer's and shading's) in the changed ranges, the camera, and
    /// what follows from the scene's extent (ray offsets, AO radius, the light when the
    /// scene has no point light); materials never change.
    fn set_frame(&mut self, frame: &SceneFrame<'_>) -> Result<(), IntegratorError> {
        if (frame.camera.width, frame.camera.height) != (self.frame.width, self.frame.height) {
            return Err(IntegratorError::Usage(
                "a frame cannot change the film size".to_string(),
            ));
        }
        self.gpu.wait_idle()?;
        if frame.geometry_changed() {
            self.tracer
                .update_geometry(frame.triangles, frame.changed)?;
            write_ranges(&self.triangles, frame.triangles, frame.changed, 1)?;
        }
        set_scene_params(
            &mut self.frame,
            &frame.camera,
            &frame.scene.bounds(),
            crate::render::shadow_light(frame.scene),
            self.ao_radius_fraction,
        );
        Ok(())
    }

    fn device_film(&self) -> Option<DeviceFilm> {
        Some(DeviceFilm {
            sums: self.accum.clone(),
            width: self.frame.width,
            height: self.frame.height,
        })
    }

    fn settings(&self) -> Vec<(String, String)> {
        // One-sample renders go through pixel centres, longer ones jitter: a film of
        // the one cannot be continued into the other.
        let mut settings = vec![("jitter".to_string(), (self.frame.jitter != 0).to_string())];
        if self.kind == IntegratorKind::Ao {
            settings.push(("ao_rays".into(), self.frame.ao_rays.to_string()));
            settings.push(("ao_radius".into(), self.frame.ao_radius.to_string()));
        }
        settings
    }
}

/// The per-chunk stages after the camera rays are traced; each returns the point that
/// marks the chunk shaded and the number of secondary rays it traced.
struct Stage<'a> {
    gpu: &'a Gpu,
    pipelines: &'a Pipelines,
    slot: &'a RaySlot,
    triangles: &'a Buffer,
    triangle_material: &'a Buffer,
    materials: &'a Buffer,
    accum: &'a Buffer,
    count: u32,
}

impl Stage<'_> {
    fn shade_primary(
        &self,
        mut rec: Recorder,
        frame: &FrameParams,
        traced: &TimelinePoint,
    ) -> vk::Result<TimelinePoint> {
        let s = self.slot;
        rec.dispatch_items(
            &self.pipelines.shade_primary,
            &[
                (&s.rays).into(),
                (&s.hits).into(),
                self.triangles.into(),
                self.triangle_material.into(),
                self.materials.into(),
                self.accum.into(),
            ],
            frame,
            self.count as u64,
        )?;
        rec.submit(&[traced])
    }

    /// The secondary-ray step every workload shares: `generate` writes `count` rays per
    /// camera hit into the slot's secondary rays (after `traced`), and the tracer casts
    /// them into the slot's secondary hits. Returns when those hits are ready.
    #[allow(clippy::too_many_arguments)]
    fn trace_secondary(
        &self,
        mut rec: Recorder,
        frame: &FrameParams,
        traced: &TimelinePoint,
        tracer: &mut dyn Tracer,
        (pipeline, bindings): (&ComputePipeline, &[BufferSlice<'_>]),
        count: u32,
        query: Query,
    ) -> vk::Result<TimelinePoint> {
        rec.dispatch_items(pipeline, bindings, frame, self.count as u64)?;
        let generated = rec.submit(&[traced])?;
        let s = self.slot;
        tracer.trace(
            &s.secondary_rays,
            &s.secondary_hits,
            count,
            query,
            &[&generated],
        )
    }

    fn ambient_occlusion(
        &self,
        rec: Recorder,
        frame: &FrameParams,
        traced: &TimelinePoint,
        tracer: &mut dyn Tracer,
    ) -> vk::Result<(TimelinePoint, u64)> {
        let s = self.slot;
        let n = self.count as u64;
        let ao_count = self.count * frame.ao_rays;
        let occluded = self.trace_secondary(
            rec,
            frame,
            traced,
            tracer,
            (
                &self.pipelines.ao_rays,
                &[
                    (&s.rays).into(),
                    (&s.hits).into(),
                    self.triangles.into(),
                    (&s.secondary_rays).into(),
                ],
            ),
            ao_count,
            Query::Occlusion,
        )?;
        let mut rec = self.gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &self.pipelines.shade_ao,
            &[
                (&s.hits).into(),
                (&s.secondary_hits).into(),
                self.accum.into(),
            ],
            frame,
            n,
        )?;
        Ok((rec.submit(&[&occluded])?, ao_count as u64))
    }

    fn shadow(
        &self,
        rec: Recorder,
        frame: &FrameParams,
        traced: &TimelinePoint,
        tracer: &mut dyn Tracer,
    ) -> vk::Result<(TimelinePoint, u64)> {
        let s = self.slot;
        let n = self.count as u64;
        let occluded = self.trace_secondary(
            rec,
            frame,
            traced,
            tracer,
            (
                &self.pipelines.shadow_rays,
                &[
                    (&s.rays).into(),
                    (&s.hits).into(),
                    self.triangles.into(),
                    self.triangle_material.into(),
                    self.materials.into(),
                    (&s.secondary_rays).into(),
                    (&s.state).into(),
                ],
            ),
            self.count,
            Query::Occlusion,
        )?;
        let mut rec = self.gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &self.pipelines.shade_shadow,
            &[
                (&s.state).into(),
                (&s.secondary_hits).into(),
                self.accum.into(),
            ],
            frame,
            n,
        )?;
        Ok((rec.submit(&[&occluded])?, n))
    }

    fn reflection(
        &self,
        rec: Recorder,
        frame: &FrameParams,
        traced: &TimelinePoint,
        tracer: &mut dyn Tracer,
    ) -> vk::Result<(TimelinePoint, u64)> {
        let s = self.slot;
        let n = self.count as u64;
        let reflected = self.trace_secondary(
            rec,
            frame,
            traced,
            tracer,
            (
                &self.pipelines.reflect_rays,
                &[
                    (&s.rays).into(),
                    (&s.hits).into(),
                    self.triangles.into(),
                    (&s.secondary_rays).into(),
                ],
            ),
            self.count,
            Query::ClosestHit,
        )?;
        // Eye-light shading of what the mirror shows, seen along the reflected ray.
        let mut rec = self.gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &self.pipelines.shade_primary,
            &[
                (&s.secondary_rays).into(),
                (&s.secondary_hits).into(),
                self.triangles.into(),
                self.triangle_material.into(),
                self.materials.into(),
                self.accum.into(),
            ],
            frame,
            n,
        )?;
        Ok((rec.submit(&[&reflected])?, n))
    }

    /// Bounce 0 shades the camera hit; each later bounce traces the ray the previous
    /// one wrote into the same buffer, in place.
    fn path(
        &self,
        mut rec: Recorder,
        frame: &mut FrameParams,
        mut traced: TimelinePoint,
        tracer: &mut dyn Tracer,
    ) -> vk::Result<(TimelinePoint, u64)> {
        let s = self.slot;
        let n = self.count as u64;
        let mut secondary = 0;
        for bounce in 0..=PATH_BOUNCES {
            frame.bounce = bounce;
            rec.dispatch_items(
                &self.pipelines.path_bounce,
                &[
                    (&s.rays).into(),
                    (&s.hits).into(),
                    self.triangles.into(),
                    self.triangle_material.into(),
                    self.materials.into(),
                    (&s.state).into(),
                    self.accum.into(),
                ],
                frame,
                n,
            )?;
            let shaded = rec.submit(&[&traced])?;
            if bounce == PATH_BOUNCES {
                frame.bounce = 0;
                return Ok((shaded, secondary));
            }
            traced = tracer.trace(&s.rays, &s.hits, self.count, Query::ClosestHit, &[&shaded])?;
            secondary += n;
            rec = self.gpu.recorder(StreamKind::Main)?;
        }
        unreachable!("the loop returns at its last bounce")
    }
}

/// Diffuse bounces of the `path` integrator after the camera hit (glsl path_bounce.comp).
const PATH_BOUNCES: u32 = 7;
