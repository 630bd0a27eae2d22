//! `pt`: a wavefront path tracer on the [`Tracer`] interface (PDACRT by default).
//!
//! A chunk is a wavefront of at most [`PtOptions::max_paths_per_chunk`] paths: several
//! whole passes (samples of every pixel) when the image is small, else a range of the
//! pixels of one pass. Per chunk and bounce, named stages run as
//! separate kernels (`glsl/integrator/pt/*.comp`):
//!
//! 1. `generate` — a path per pixel and its camera ray (box filter: uniform jitter);
//! 2. trace — closest hits of the live paths' rays;
//! 3. `sort_keys` + radix sort (optional, [`PtOptions::sort`]) — the live paths ordered
//!    by the material key of their hit (misses last) so that shading is coherent;
//! 4. `shade` — emission with MIS, next-event estimation (a shadow ray and its
//!    unoccluded contribution), BSDF sampling and Russian roulette, exactly in the order
//!    of Mitsuba 3's `path` integrator;
//! 5. trace (occlusion) — the shadow rays;
//! 6. `nee_accumulate` — unoccluded contributions join their path's radiance;
//! 7. compaction ([`Compact`]) + `gather` — the surviving paths' rays and ids move to
//!    the front, in their original order, and the host reads how many survived (the
//!    tracer takes a host-side ray count) before the next bounce;
//! 8. `finish` — each path's radiance is one sample of its pixel (sum and sum of
//!    squares, for standard errors).
//!
//! **Depth** counts as in Mitsuba: `max_depth` = 1 shows only emitters seen directly,
//! 2 adds direct lighting, and so on; a negative `max_depth` is unbounded. Russian
//! roulette starts at depth `rr_depth` (Mitsuba's default 5) with survival probability
//! min(max(β)·η², 0.95).
//!
//! **Determinism.** Random numbers are a pure function of (pixel, sample, dimension,
//! seed) (`glsl/common/random.glsl`); every stage writes by the path's position in the
//! unsorted active list, and compaction keeps the order. So the same seed gives the same
//! image on the same device, and sorting on or off gives a bit-identical film.

pub mod gpu;
pub mod lights;
pub mod materials;

use std::time::Instant;

use glam::Vec3;

use self::gpu::{PathState, PtMaterial, PtParams, FLAG_BSDF, FLAG_NEE, FLAG_SORTED};
pub use self::lights::LightTable;
use crate::bsdf::BsdfParams;
use crate::primitives::compact::Kept;
use crate::primitives::{Compact, RadixSort, Tuning};
use crate::scene::{CameraFrame, Scene};
use crate::shaders;
use crate::trace::{GpuTriangle, Hit, Query, Ray, Tracer};
use crate::vk::{self, Buffer, ComputePipeline, Gpu, MemoryKind, StreamKind};

const WORKGROUP: u32 = 64;

/// Which estimators contribute light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Strategy {
    /// Light sampling and BSDF sampling, combined by the power heuristic.
    #[default]
    Mis,
    /// Light sampling only (emitters hit by BSDF sampling count only after delta lobes
    /// or on camera rays).
    Nee,
    /// BSDF sampling only (no shadow rays).
    Bsdf,
}

impl std::str::FromStr for Strategy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "mis" => Ok(Self::Mis),
            "nee" => Ok(Self::Nee),
            "bsdf" => Ok(Self::Bsdf),
            _ => Err(format!(
                "unknown strategy '{s}' (choose one of: mis, nee, bsdf)"
            )),
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct PtOptions {
    /// Passes (samples per pixel); with `time_limit`, the most passes.
    pub spp: u32,
    /// Stop after the pass during which this many seconds ran out.
    pub time_limit: Option<f64>,
    pub seed: u64,
    /// Mitsuba's `max_depth`: 1 = emitters seen directly, 2 = direct light; < 0 unbounded.
    pub max_depth: i32,
    /// Mitsuba's `rr_depth`: Russian roulette from this depth on.
    pub rr_depth: u32,
    /// Sort live paths by material key before shading.
    pub sort: bool,
    pub strategy: Strategy,
    /// Upper bound on paths per chunk (bounds memory).
    pub max_paths_per_chunk: u32,
}

impl Default for PtOptions {
    fn default() -> Self {
        Self {
            spp: 1,
            time_limit: None,
            seed: 0,
            max_depth: -1,
            rr_depth: 5,
            sort: true,
            strategy: Strategy::Mis,
            max_paths_per_chunk: 1 << 19,
        }
    }
}

/// The scene as the path tracer's kernels read it.
pub struct PtScene {
    pub triangles: Vec<GpuTriangle>,
    pub triangle_material: Vec<u32>,
    pub materials: Vec<PtMaterial>,
    pub bsdfs: Vec<BsdfParams>,
    /// Three per triangle: shading normals, w = 1 where the triangle has them.
    pub normals: Vec<[f32; 4]>,
    pub lights: LightTable,
    /// Radius of the scene's bounding sphere (scales ray offsets).
    pub scene_radius: f32,
}

impl PtScene {
    pub fn new(scene: &Scene) -> Self {
        let (bsdfs, materials) = materials::material_tables(&scene.materials);
        let normals = if scene.triangles.iter().any(|t| t.n.is_some()) {
            scene
                .triangles
                .iter()
                .flat_map(|t| match t.n {
                    Some(n) => n.map(|v| v.extend(1.0).into()),
                    None => [[0.0; 4]; 3],
                })
                .collect()
        } else {
            vec![[0.0; 4]; 3]
        };
        let _ = Vec3::ZERO;
        Self {
            triangles: scene
                .triangles
                .iter()
                .map(|t| GpuTriangle::new(t.p))
                .collect(),
            triangle_material: scene.triangles.iter().map(|t| t.material).collect(),
            materials,
            bsdfs,
            normals,
            lights: LightTable::new(scene),
            scene_radius: scene.bounds().radius(),
        }
    }
}

/// What the passes produced.
pub struct PtOutput {
    /// Per pixel: Σ L (rgb) and the number of samples (w).
    pub sum_rgb: Vec<[f32; 4]>,
    /// Per pixel: Σ L² (rgb).
    pub sum_sq: Vec<[f32; 4]>,
    /// Passes (samples per pixel) taken.
    pub passes: u32,
    /// Rays cast: path rays plus shadow rays.
    pub rays_traced: u64,
}

impl PtOutput {
    /// Per-pixel mean and standard error of the mean (rgb).
    pub fn mean_and_stderr(&self) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
        self.sum_rgb
            .iter()
            .zip(&self.sum_sq)
            .map(|(s, q)| {
                let n = s[3].max(1.0) as f64;
                let mut mean = [0.0; 3];
                let mut se = [0.0; 3];
                for c in 0..3 {
                    let m = s[c] as f64 / n;
                    let var = (q[c] as f64 / n - m * m).max(0.0) * n / (n - 1.0).max(1.0);
                    mean[c] = m as f32;
                    se[c] = (var / n).sqrt() as f32;
                }
                (mean, se)
            })
            .unzip()
    }
}

struct Pipelines {
    generate: ComputePipeline,
    sort_keys: ComputePipeline,
    shade: ComputePipeline,
    nee_accumulate: ComputePipeline,
    gather: ComputePipeline,
    finish: ComputePipeline,
}

impl Pipelines {
    fn new(gpu: &Gpu) -> vk::Result<Self> {
        let make = |kernel, bindings| {
            vk::compute_pipeline(
                gpu,
                kernel,
                bindings,
                size_of::<PtParams>() as u32,
                &[WORKGROUP],
            )
        };
        Ok(Self {
            generate: make(shaders::INTEGRATOR_PT_GENERATE, 3)?,
            sort_keys: make(shaders::INTEGRATOR_PT_SORT_KEYS, 5)?,
            shade: make(shaders::INTEGRATOR_PT_SHADE, 16)?,
            nee_accumulate: make(shaders::INTEGRATOR_PT_NEE_ACCUMULATE, 4)?,
            gather: make(shaders::INTEGRATOR_PT_GATHER, 5)?,
            finish: make(shaders::INTEGRATOR_PT_FINISH, 3)?,
        })
    }
}

/// Uploads `data`, or one zeroed element when it is empty (bindings need a buffer).
fn upload_or_dummy<T: bytemuck::Pod>(gpu: &Gpu, name: &str, data: &[T]) -> vk::Result<Buffer> {
    if data.is_empty() {
        gpu.upload(name, &[T::zeroed()])
    } else {
        gpu.upload(name, data)
    }
}

/// Renders passes until `options.spp` are done or `options.time_limit` ran out;
/// `progress` is called with the number of passes done.
pub fn render_pt(
    gpu: &Gpu,
    tracer: &mut dyn Tracer,
    scene: &PtScene,
    camera: &CameraFrame,
    options: &PtOptions,
    progress: &mut dyn FnMut(u32),
) -> vk::Result<PtOutput> {
    let start = Instant::now();
    let pipelines = Pipelines::new(gpu)?;
    let tuning = Tuning::for_device(gpu.info());
    let pixels = camera.width as usize * camera.height as usize;
    let max_paths = options.max_paths_per_chunk.max(1) as usize;
    // Whole passes per chunk when the image is small, else one pass in pixel ranges.
    let passes_per_chunk = (max_paths / pixels.max(1)).clamp(1, options.spp.max(1) as usize);
    let pixels_per_chunk = pixels.min(max_paths);
    let c = passes_per_chunk * pixels_per_chunk;
    let chunk = c as u32;

    let triangles = gpu.upload("pt-triangles", &scene.triangles)?;
    let triangle_material = gpu.upload("pt-triangle-material", &scene.triangle_material)?;
    let materials = upload_or_dummy(gpu, "pt-materials", &scene.materials)?;
    let bsdfs = upload_or_dummy(gpu, "pt-bsdfs", &scene.bsdfs)?;
    let normals = upload_or_dummy(gpu, "pt-normals", &scene.normals)?;
    let lights = upload_or_dummy(gpu, "pt-lights", &scene.lights.lights)?;
    let light_cdf = upload_or_dummy(gpu, "pt-light-cdf", &scene.lights.cdf)?;
    let tri_pmf = upload_or_dummy(gpu, "pt-tri-light-pmf", &scene.lights.tri_pmf)?;

    let accum = gpu.zeroed::<[f32; 4]>("pt-accum", pixels)?;
    let accum2 = gpu.zeroed::<[f32; 4]>("pt-accum2", pixels)?;
    let rays = [
        gpu.zeroed::<Ray>("pt-rays-0", c)?,
        gpu.zeroed::<Ray>("pt-rays-1", c)?,
    ];
    let active = [
        gpu.zeroed::<u32>("pt-active-0", c)?,
        gpu.zeroed::<u32>("pt-active-1", c)?,
    ];
    let hits = gpu.zeroed::<Hit>("pt-hits", c)?;
    let paths = gpu.zeroed::<PathState>("pt-paths", c)?;
    let keys = gpu.zeroed::<u32>("pt-keys", c)?;
    let order = gpu.zeroed::<u32>("pt-order", c)?;
    let shadow_rays = gpu.zeroed::<Ray>("pt-shadow-rays", c)?;
    let shadow_hits = gpu.zeroed::<Hit>("pt-shadow-hits", c)?;
    let nee = gpu.zeroed::<[f32; 4]>("pt-nee", c)?;
    let alive = gpu.zeroed::<u32>("pt-alive", c)?;
    let kept = gpu.zeroed::<u32>("pt-kept", c)?;
    let count = gpu.create_buffer("pt-count", 4, MemoryKind::Readback)?;

    let compact = Compact::new(gpu, &tuning)?;
    let compact_scratch = gpu.create_buffer(
        "pt-compact-scratch",
        compact.scratch_bytes(chunk),
        MemoryKind::Device,
    )?;
    let sorter = if options.sort {
        let sort = RadixSort::new(gpu, &tuning)?;
        let scratch = sort.alloc_scratch(gpu, chunk)?;
        Some((sort, scratch))
    } else {
        None
    };

    let mut params = PtParams::new(camera);
    params.seed = options.seed as u32 ^ (options.seed >> 32) as u32;
    params.max_depth = options.max_depth;
    params.rr_depth = options.rr_depth;
    params.light_count = scene.lights.lights.len() as u32;
    params.ray_epsilon = 1e-4 * scene.scene_radius.max(1e-3);
    let nee_on = options.strategy != Strategy::Bsdf && params.light_count > 0;
    params.flags = match options.strategy {
        Strategy::Mis => FLAG_NEE | FLAG_BSDF,
        Strategy::Nee => FLAG_NEE,
        Strategy::Bsdf => FLAG_BSDF,
    };
    if sorter.is_some() {
        params.flags |= FLAG_SORTED;
    }

    let mut rays_traced = 0u64;
    let mut passes = 0u32;
    while passes < options.spp {
        let batch = (passes_per_chunk as u32).min(options.spp - passes);
        params.sample_index = passes;
        for offset in (0..pixels).step_by(pixels_per_chunk) {
            let pixel_count = pixels_per_chunk.min(pixels - offset) as u32;
            let n0 = pixel_count * batch;
            params.pixel_offset = offset as u32;
            params.pixel_count = pixel_count;
            params.path_count = n0;
            let mut rec = gpu.recorder(StreamKind::Main)?;
            rec.dispatch_items(
                &pipelines.generate,
                &[(&rays[0]).into(), (&active[0]).into(), (&paths).into()],
                &params,
                n0 as u64,
            )?;
            let mut ready = rec.submit(&[])?;
            let mut cur = 0usize;
            let mut n = n0;
            let mut bounce = 0u32;
            while n > 0 {
                params.active_count = n;
                params.bounce = bounce;
                let traced = tracer.trace(&rays[cur], &hits, n, Query::ClosestHit, &[&ready])?;
                rays_traced += n as u64;

                let mut rec = gpu.recorder(StreamKind::Main)?;
                if let Some((sort, scratch)) = &sorter {
                    rec.dispatch_items(
                        &pipelines.sort_keys,
                        &[
                            (&hits).into(),
                            (&triangle_material).into(),
                            (&materials).into(),
                            (&keys).into(),
                            (&order).into(),
                        ],
                        &params,
                        n as u64,
                    )?;
                    rec.barrier();
                    sort.record(
                        &mut rec,
                        n,
                        (&keys).into(),
                        Some((&order).into()),
                        0..32,
                        scratch,
                    )?;
                }
                rec.dispatch_items(
                    &pipelines.shade,
                    &[
                        (&rays[cur]).into(),
                        (&hits).into(),
                        (&active[cur]).into(),
                        (&order).into(),
                        (&paths).into(),
                        (&triangles).into(),
                        (&triangle_material).into(),
                        (&materials).into(),
                        (&bsdfs).into(),
                        (&normals).into(),
                        (&lights).into(),
                        (&light_cdf).into(),
                        (&tri_pmf).into(),
                        (&shadow_rays).into(),
                        (&nee).into(),
                        (&alive).into(),
                    ],
                    &params,
                    n as u64,
                )?;
                let shaded = rec.submit(&[&traced])?;

                let mut rec = gpu.recorder(StreamKind::Main)?;
                let after = if nee_on {
                    let occluded = tracer.trace(
                        &shadow_rays,
                        &shadow_hits,
                        n,
                        Query::Occlusion,
                        &[&shaded],
                    )?;
                    rays_traced += n as u64;
                    rec.dispatch_items(
                        &pipelines.nee_accumulate,
                        &[
                            (&active[cur]).into(),
                            (&shadow_hits).into(),
                            (&nee).into(),
                            (&paths).into(),
                        ],
                        &params,
                        n as u64,
                    )?;
                    occluded
                } else {
                    shaded
                };
                compact.record(
                    &mut rec,
                    n,
                    (&alive).into(),
                    Kept::Indices,
                    (&kept).into(),
                    (&count).into(),
                    &compact_scratch,
                )?;
                let compacted = rec.submit(&[&after])?;
                gpu.wait(&compacted)?;
                let survivors = count.read::<u32>()?[0].min(n);
                if survivors == 0 {
                    break;
                }
                params.active_count = survivors;
                let mut rec = gpu.recorder(StreamKind::Main)?;
                rec.dispatch_items(
                    &pipelines.gather,
                    &[
                        (&kept).into(),
                        (&rays[cur]).into(),
                        (&active[cur]).into(),
                        (&rays[1 - cur]).into(),
                        (&active[1 - cur]).into(),
                    ],
                    &params,
                    survivors as u64,
                )?;
                ready = rec.submit(&[])?;
                cur = 1 - cur;
                n = survivors;
                bounce += 1;
            }
            let mut rec = gpu.recorder(StreamKind::Main)?;
            rec.dispatch_items(
                &pipelines.finish,
                &[(&paths).into(), (&accum).into(), (&accum2).into()],
                &params,
                pixel_count as u64,
            )?;
            let done = rec.submit(&[])?;
            gpu.wait(&done)?;
        }
        passes += batch;
        progress(passes);
        if let Some(limit) = options.time_limit {
            if start.elapsed().as_secs_f64() >= limit {
                break;
            }
        }
    }
    gpu.wait_idle()?;
    Ok(PtOutput {
        sum_rgb: accum.read()?,
        sum_sq: accum2.read()?,
        passes,
        rays_traced,
    })
}
