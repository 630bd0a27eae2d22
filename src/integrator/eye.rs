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
    self, Buffer, ComputePipeline, Gpu, MemoryKind, PipelineDesc, StreamKind, TimelinePoint,
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
}

impl Pipelines {
    fn new(gpu: &Gpu) -> vk::Result<Self> {
        let make = |kernel, bindings| {
            ComputePipeline::new(
                gpu,
                &PipelineDesc {
                    kernel,
                    bindings,
                    push_constant_bytes: size_of::<FrameParams>() as u32,
                    spec: &[WORKGROUP],
                },
            )
        };
        Ok(Self {
            camera_rays: make(shaders::INTEGRATOR_CAMERA_RAYS, 1)?,
            write_aovs: make(shaders::INTEGRATOR_WRITE_AOVS, 6)?,
            shade_primary: make(shaders::INTEGRATOR_SHADE_PRIMARY, 6)?,
            ao_rays: make(shaders::INTEGRATOR_AO_RAYS, 4)?,
            shade_ao: make(shaders::INTEGRATOR_SHADE_AO, 3)?,
        })
    }
}

/// One set of ray and hit buffers for a chunk.
struct RaySlot {
    rays: Buffer,
    hits: Buffer,
    ao_rays: Buffer,
    ao_hits: Buffer,
}

impl RaySlot {
    fn new(gpu: &Gpu, index: usize, chunk: u64, ao_rays: u64) -> vk::Result<Self> {
        let ray = size_of::<Ray>() as u64;
        let hit = size_of::<Hit>() as u64;
        let buffer = |name: &str, bytes| {
            gpu.create_buffer(&format!("{name}-{index}"), bytes, MemoryKind::Device)
        };
        Ok(Self {
            rays: buffer("rays", chunk * ray)?,
            hits: buffer("hits", chunk * hit)?,
            ao_rays: buffer("ao-rays", chunk * ao_rays * ray)?,
            ao_hits: buffer("ao-hits", chunk * ao_rays * hit)?,
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
    let ao = options.integrator == IntegratorKind::Ao;
    let ao_rays = if ao { options.ao_rays.max(1) } else { 0 };
    let chunk = (options.max_rays_per_chunk / (1 + ao_rays)).clamp(1, pixels.max(1) as u32);

    let triangles = gpu.upload("shade-triangles", inputs.triangles)?;
    let triangle_material = gpu.upload("triangle-material", inputs.triangle_material)?;
    let materials = gpu.upload("materials", inputs.materials)?;
    let accum = gpu.zeroed::<[f32; 4]>("accum", pixels)?;
    let depth = gpu.zeroed::<f32>("aov-depth", pixels)?;
    let triangle_id = gpu.zeroed::<u32>("aov-triangle-id", pixels)?;
    let normal = gpu.zeroed::<[f32; 4]>("aov-normal", pixels)?;
    let slots = [
        RaySlot::new(gpu, 0, chunk as u64, ao_rays as u64)?,
        RaySlot::new(gpu, 1, chunk as u64, ao_rays as u64)?,
    ];

    let mut frame = FrameParams::new(&inputs.camera);
    frame.seed = options.seed as u32 ^ (options.seed >> 32) as u32;
    frame.jitter = (options.spp > 1) as u32;
    frame.ao_rays = ao_rays;
    frame.ao_radius = options.ao_radius_fraction * inputs.scene_radius;
    frame.ray_epsilon = 1e-4 * inputs.scene_radius.max(1e-3);

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
            let done = if ao {
                rec.dispatch_items(
                    &pipelines.ao_rays,
                    &[
                        (&slot.rays).into(),
                        (&slot.hits).into(),
                        (&triangles).into(),
                        (&slot.ao_rays).into(),
                    ],
                    &frame,
                    n,
                )?;
                let generated = rec.submit(&[&traced])?;
                let ao_count = count * ao_rays;
                let occluded = tracer.trace(
                    &slot.ao_rays,
                    &slot.ao_hits,
                    ao_count,
                    Query::Occlusion,
                    &[&generated],
                )?;
                rays_traced += ao_count as u64;
                let mut rec = gpu.recorder(StreamKind::Main)?;
                rec.dispatch_items(
                    &pipelines.shade_ao,
                    &[(&slot.hits).into(), (&slot.ao_hits).into(), (&accum).into()],
                    &frame,
                    n,
                )?;
                rec.submit(&[&occluded])?
            } else {
                rec.dispatch_items(
                    &pipelines.shade_primary,
                    &[
                        (&slot.rays).into(),
                        (&slot.hits).into(),
                        (&triangles).into(),
                        (&triangle_material).into(),
                        (&materials).into(),
                        (&accum).into(),
                    ],
                    &frame,
                    n,
                )?;
                rec.submit(&[&traced])?
            };
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
