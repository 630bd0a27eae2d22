//! The `primary` and `ao` integrators: one camera sample per pixel per pass, processed
//! in chunks of pixels small enough that every ray buffer fits one storage binding.
//!
//! Stages per chunk (each a named dispatch): `camera_rays` → trace → `write_aovs`
//! (sample 0) → `shade_primary`, or for AO: → `ao_rays` → trace (occlusion) → `shade_ao`.

use super::gpu_types::{FrameParams, GpuMaterial};
use super::IntegratorKind;
use crate::scene::CameraFrame;
use crate::shaders;
use crate::trace::{GpuTriangle, Hit, Query, Ray, Tracer};
use crate::vk::{
    self, Buffer, BufferSlice, ComputePipeline, Gpu, MemoryKind, Recorder, StreamKind,
    TimelinePoint,
};

const WORKGROUP: u32 = 64;

/// Scene data the shading kernels read.
pub struct PassInputs<'a> {
    pub triangles: &'a [GpuTriangle],
    pub triangle_material: &'a [u32],
    pub materials: &'a [GpuMaterial],
    pub camera: CameraFrame,
    /// Radius of the scene's bounding sphere: scales the AO radius and ray offsets.
    pub scene_radius: f32,
    /// The shadow integrator's point light: position and intensity (W/sr).
    pub light: glam::Vec4,
}

#[derive(Clone, Copy, Debug)]
pub struct PassOptions {
    pub integrator: IntegratorKind,
    pub spp: u32,
    pub seed: u64,
    pub ao_rays: u32,
    /// AO rays reach this fraction of the scene radius.
    pub ao_radius_fraction: f32,
    /// Upper bound on rays per chunk (bounds memory).
    pub max_rays_per_chunk: u32,
}

impl Default for PassOptions {
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

/// What the passes produced: the per-pixel sum of all samples (w = sample count) and
/// the first-hit AOVs of sample 0.
pub struct IntegratorOutput {
    pub sum_rgb: Vec<[f32; 4]>,
    pub depth: Vec<f32>,
    pub triangle_id: Vec<u32>,
    pub normal: Vec<[f32; 4]>,
    pub rays_traced: u64,
}

struct Pipelines {
    camera_rays: ComputePipeline,
    write_aovs: ComputePipeline,
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
            write_aovs: make(shaders::INTEGRATOR_WRITE_AOVS, 6)?,
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

/// Renders `options.spp` passes; `progress` is called with the number of passes done.
/// Two chunks are in flight at most: the host waits only to reuse a chunk's buffers.
pub fn render_passes(
    gpu: &Gpu,
    tracer: &mut dyn Tracer,
    inputs: &PassInputs<'_>,
    options: &PassOptions,
    progress: &mut dyn FnMut(u32),
) -> vk::Result<IntegratorOutput> {
    let pipelines = Pipelines::new(gpu)?;
    let pixels = inputs.camera.width as usize * inputs.camera.height as usize;
    let kind = options.integrator;
    let ao_rays = options.ao_rays.max(1);
    let per_pixel = match kind {
        IntegratorKind::Ao => ao_rays,
        IntegratorKind::Shadow | IntegratorKind::Reflection => 1,
        IntegratorKind::Primary | IntegratorKind::Path => 0,
        IntegratorKind::Pt => {
            return Err(vk::VkError::Usage(
                "the pt integrator renders through integrator::pt::render_pt".into(),
            ))
        }
    };
    let chunk = (options.max_rays_per_chunk / (1 + per_pixel)).clamp(1, pixels.max(1) as u32);

    let triangles = gpu.upload("shade-triangles", inputs.triangles)?;
    let triangle_material = gpu.upload("triangle-material", inputs.triangle_material)?;
    let materials = gpu.upload("materials", inputs.materials)?;
    let accum = gpu.zeroed::<[f32; 4]>("accum", pixels)?;
    let depth = gpu.zeroed::<f32>("aov-depth", pixels)?;
    let triangle_id = gpu.zeroed::<u32>("aov-triangle-id", pixels)?;
    let normal = gpu.zeroed::<[f32; 4]>("aov-normal", pixels)?;
    let slots = [
        RaySlot::new(gpu, 0, chunk as u64, per_pixel as u64)?,
        RaySlot::new(gpu, 1, chunk as u64, per_pixel as u64)?,
    ];

    let mut frame = FrameParams::new(&inputs.camera);
    frame.seed = options.seed as u32 ^ (options.seed >> 32) as u32;
    frame.jitter = (options.spp > 1) as u32;
    frame.ao_rays = ao_rays;
    frame.ao_radius = options.ao_radius_fraction * inputs.scene_radius;
    frame.ray_epsilon = 1e-4 * inputs.scene_radius.max(1e-3);
    frame.light = inputs.light.into();

    let mut rays_traced = 0u64;
    let mut in_flight: [Option<TimelinePoint>; 2] = [None, None];
    let mut step = 0usize;
    for sample in 0..options.spp {
        frame.sample_index = sample;
        for offset in (0..pixels).step_by(chunk as usize) {
            let count = chunk.min((pixels - offset) as u32);
            frame.pixel_offset = offset as u32;
            frame.pixel_count = count;
            let slot = &slots[step % 2];
            if let Some(previous) = in_flight[step % 2].take() {
                gpu.wait(&previous)?;
            }
            let n = count as u64;

            let mut rec = gpu.recorder(StreamKind::Main)?;
            rec.dispatch_items(&pipelines.camera_rays, &[(&slot.rays).into()], &frame, n)?;
            let generated = rec.submit(&[])?;
            let traced = tracer.trace(
                &slot.rays,
                &slot.hits,
                count,
                Query::ClosestHit,
                &[&generated],
            )?;
            rays_traced += n;

            let mut rec = gpu.recorder(StreamKind::Main)?;
            if sample == 0 {
                rec.dispatch_items(
                    &pipelines.write_aovs,
                    &[
                        (&slot.rays).into(),
                        (&slot.hits).into(),
                        (&triangles).into(),
                        (&depth).into(),
                        (&triangle_id).into(),
                        (&normal).into(),
                    ],
                    &frame,
                    n,
                )?;
            }
            let stage = Stage {
                gpu,
                pipelines: &pipelines,
                slot,
                triangles: &triangles,
                triangle_material: &triangle_material,
                materials: &materials,
                accum: &accum,
                count,
            };
            let (done, secondary) = match kind {
                IntegratorKind::Primary => (stage.shade_primary(rec, &frame, &traced)?, 0),
                IntegratorKind::Ao => stage.ambient_occlusion(rec, &frame, &traced, tracer)?,
                IntegratorKind::Shadow => stage.shadow(rec, &frame, &traced, tracer)?,
                IntegratorKind::Reflection => stage.reflection(rec, &frame, &traced, tracer)?,
                IntegratorKind::Path => stage.path(rec, &mut frame, traced, tracer)?,
                IntegratorKind::Pt => unreachable!("refused before the loop"),
            };
            rays_traced += secondary;
            in_flight[step % 2] = Some(done);
            step += 1;
        }
        progress(sample + 1);
    }
    gpu.wait_idle()?;
    Ok(IntegratorOutput {
        sum_rgb: accum.read()?,
        depth: depth.read()?,
        triangle_id: triangle_id.read()?,
        normal: normal.read()?,
        rays_traced,
    })
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
