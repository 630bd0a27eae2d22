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

mod frame;
pub mod gpu;
pub mod lights;
mod material_sort;
pub mod materials;
pub mod twin;

use std::sync::Arc;
use std::time::Instant;

use self::gpu::{PathState, PtMaterial, PtParams, FLAG_BSDF, FLAG_NEE, FLAG_NORMALS, FLAG_SORTED};
pub use self::lights::LightTable;
pub(crate) use self::material_sort::MaterialSort;
use super::{check_film_size, Integrator, IntegratorError, IntegratorStats, SceneFrame};
use crate::bsdf::BsdfParams;
use crate::film::{DeviceFilm, FilmSums};
use crate::primitives::compact::Kept;
use crate::primitives::{Compact, Tuning};
use crate::scene::{Aabb, CameraFrame, Scene};
use crate::shaders;
use crate::trace::{GpuTriangle, Hit, Query, Ray, Tracer};
use crate::vk::{self, Buffer, ComputePipeline, Gpu, MemoryKind, StreamKind, TimelinePoint};

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

/// Whether sorting paths by material pays for `pt` on `gpu`, as measured
/// (docs/PERFORMANCE.md): not on CPU implementations (lavapipe), where it costs 5–20 %
/// (`splitray bench pt` on the Cornell box and lamps); on GPUs, where divergent shading
/// serialises SIMT groups, it stays the default (`pt` is not measured on one yet).
pub fn sort_pays(gpu: &Gpu) -> bool {
    !gpu.info().is_cpu()
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
    /// The scene's bounds.
    pub bounds: Aabb,
    /// How far rays leaving a surface start off it ([`Aabb::ray_epsilon`]).
    pub ray_epsilon: f32,
}

impl PtScene {
    /// Whether `normals` holds three per triangle. Without them the table the kernels
    /// get is one dummy entry: reading it at a triangle's index would be out of bounds,
    /// and no robustness promises zeros there (through a buffer address nothing does).
    pub fn has_normals(&self) -> bool {
        !self.triangles.is_empty() && self.normals.len() == 3 * self.triangles.len()
    }

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
        let bounds = scene.bounds();
        let ray_epsilon = bounds.ray_epsilon(scene.ray_sources());
        Self {
            triangles: scene.gpu_triangles(),
            triangle_material: scene.triangles.iter().map(|t| t.material).collect(),
            materials,
            bsdfs,
            normals,
            lights: LightTable::new(scene),
            bounds,
            ray_epsilon,
        }
    }
}

/// What the passes produced.
pub struct PtOutput {
    /// Per pixel Σ L (rgb) and the number of samples (w), then their remainders: a film
    /// of sums in two floats ([`compensated`](crate::film::compensated)).
    pub sum_rgb: Vec<[f32; 4]>,
    /// Per pixel Σ (s L)² (rgb), s = `brightness_scale`, then their remainders.
    pub sum_sq: Vec<[f32; 4]>,
    /// The power of two samples were multiplied by before they were squared
    /// ([`LightTable::brightness_scale`]).
    pub brightness_scale: f32,
    /// The film's width and height.
    pub size: [u32; 2],
    /// Passes (samples per pixel) taken.
    pub passes: u32,
    /// Rays cast: path rays plus shadow rays.
    pub rays_traced: u64,
    /// Samples whose radiance was NaN or infinite: each was added as zero.
    pub non_finite_dropped: u64,
}

impl PtOutput {
    /// Per pixel Σ L (rgb) and the number of samples (w), each the f32 nearest to the
    /// sum (the first half of [`PtOutput::sum_rgb`]).
    pub fn pixel_sums(&self) -> &[[f32; 4]] {
        &self.sum_rgb[..self.sum_rgb.len() / 2]
    }

    /// The film's sums (one sample per pass).
    pub fn sums(&self) -> FilmSums {
        let [width, height] = self.size;
        FilmSums::from_gpu(
            width,
            height,
            self.passes,
            1,
            &self.sum_rgb,
            Some(&self.sum_sq),
            self.brightness_scale,
        )
    }

    /// Per-pixel mean and standard error of the mean (rgb; zero before two passes).
    pub fn mean_and_stderr(&self) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
        let sums = self.sums();
        let stderr = sums
            .stderr()
            .unwrap_or_else(|| vec![[0.0; 3]; sums.pixel_count()]);
        (sums.mean(), stderr)
    }
}

struct Pipelines {
    generate: ComputePipeline,
    shade: ComputePipeline,
    nee_accumulate: ComputePipeline,
    gather: ComputePipeline,
    finish: ComputePipeline,
}

impl Pipelines {
    /// `pt`'s kernels; the shading kernel compiled for the layer kinds in `bsdf_kinds`
    /// alone ([`crate::bsdf::layer_kinds`]).
    fn new(gpu: &Gpu, bsdf_kinds: u32) -> vk::Result<Self> {
        let with_constants = |kernel, bindings, constants: &[u32]| {
            vk::compute_pipeline(
                gpu,
                kernel,
                bindings,
                size_of::<PtParams>() as u32,
                constants,
            )
        };
        let make = |kernel, bindings| with_constants(kernel, bindings, &[WORKGROUP]);
        Ok(Self {
            generate: make(shaders::INTEGRATOR_PT_GENERATE, 3)?,
            shade: with_constants(
                shaders::INTEGRATOR_PT_SHADE,
                16,
                &crate::bsdf::kernel_constants(WORKGROUP, 1, bsdf_kinds),
            )?,
            nee_accumulate: make(shaders::INTEGRATOR_PT_NEE_ACCUMULATE, 4)?,
            gather: make(shaders::INTEGRATOR_PT_GATHER, 5)?,
            finish: make(shaders::INTEGRATOR_PT_FINISH, 4)?,
        })
    }
}

/// Uploads `data`, or one zeroed element when it is empty (bindings need a buffer).
pub(crate) fn upload_or_dummy<T: bytemuck::Pod>(
    gpu: &Gpu,
    name: &str,
    data: &[T],
) -> vk::Result<Buffer> {
    if data.is_empty() {
        gpu.upload(name, &[T::zeroed()])
    } else {
        gpu.upload(name, data)
    }
}

/// Rewrites second moments summed at brightness scale `from` (Σ (from · L)²) as sums at
/// `to`, where a new frame changed the scale and the film is kept. Exact: the factor is
/// a power of two, which keeps the sums' remainders canonical too.
pub(crate) fn rescale_moments(sum_sq: &Buffer, from: f32, to: f32) -> vk::Result<()> {
    if from == to {
        return Ok(());
    }
    let by = (to as f64 / from as f64).powi(2);
    let q: Vec<[f32; 4]> = sum_sq.read()?;
    let times = |x: f32| (x as f64 * by) as f32;
    let rescaled: Vec<[f32; 4]> = q
        .iter()
        .map(|v| [times(v[0]), times(v[1]), times(v[2]), v[3]])
        .collect();
    sum_sq.write(&rescaled)
}

/// The scene as the shading kernels read it (`pt`'s and the light-vertex-cache
/// integrators').
pub struct SceneBuffers {
    pub(crate) triangles: Buffer,
    pub(crate) triangle_material: Buffer,
    pub(crate) materials: Buffer,
    pub(crate) bsdfs: Buffer,
    pub(crate) normals: Buffer,
    pub(crate) lights: Buffer,
    pub(crate) light_cdf: Buffer,
    pub(crate) tri_pmf: Buffer,
    /// Entries of `materials`.
    pub(crate) material_count: u32,
}

impl SceneBuffers {
    pub(crate) fn new(gpu: &Gpu, scene: &PtScene) -> vk::Result<Self> {
        Ok(Self {
            triangles: gpu.upload("pt-triangles", &scene.triangles)?,
            triangle_material: gpu.upload("pt-triangle-material", &scene.triangle_material)?,
            materials: upload_or_dummy(gpu, "pt-materials", &scene.materials)?,
            bsdfs: upload_or_dummy(gpu, "pt-bsdfs", &scene.bsdfs)?,
            normals: upload_or_dummy(gpu, "pt-normals", &scene.normals)?,
            lights: upload_or_dummy(gpu, "pt-lights", &scene.lights.lights)?,
            light_cdf: upload_or_dummy(gpu, "pt-light-cdf", &scene.lights.cdf)?,
            tri_pmf: upload_or_dummy(gpu, "pt-tri-light-pmf", &scene.lights.tri_pmf)?,
            material_count: scene.materials.len() as u32,
        })
    }
}

/// The wavefront's per-path buffers, `chunk` paths each (two of the ray and active
/// lists: compaction gathers survivors from one into the other).
struct Wavefront {
    rays: [Buffer; 2],
    active: [Buffer; 2],
    hits: Buffer,
    paths: Buffer,
    keys: Buffer,
    order: Buffer,
    shadow_rays: Buffer,
    shadow_hits: Buffer,
    nee: Buffer,
    alive: Buffer,
    kept: Buffer,
    count: Buffer,
    compact: Compact,
    compact_scratch: Buffer,
    sorter: Option<MaterialSort>,
}

impl Wavefront {
    fn new(gpu: &Gpu, c: usize, sort: bool) -> vk::Result<Self> {
        let tuning = Tuning::for_device(gpu.info());
        let compact = Compact::new(gpu, &tuning)?;
        let compact_scratch = gpu.create_buffer(
            "pt-compact-scratch",
            compact.scratch_bytes(c as u32),
            MemoryKind::Device,
        )?;
        let sorter = sort
            .then(|| MaterialSort::new(gpu, &tuning, c as u32))
            .transpose()?;
        Ok(Self {
            rays: [
                gpu.zeroed::<Ray>("pt-rays-0", c)?,
                gpu.zeroed::<Ray>("pt-rays-1", c)?,
            ],
            active: [
                gpu.zeroed::<u32>("pt-active-0", c)?,
                gpu.zeroed::<u32>("pt-active-1", c)?,
            ],
            hits: gpu.zeroed::<Hit>("pt-hits", c)?,
            paths: gpu.zeroed::<PathState>("pt-paths", c)?,
            keys: gpu.zeroed::<u32>("pt-keys", c)?,
            order: gpu.zeroed::<u32>("pt-order", c)?,
            shadow_rays: gpu.zeroed::<Ray>("pt-shadow-rays", c)?,
            shadow_hits: gpu.zeroed::<Hit>("pt-shadow-hits", c)?,
            nee: gpu.zeroed::<[f32; 4]>("pt-nee", c)?,
            alive: gpu.zeroed::<u32>("pt-alive", c)?,
            kept: gpu.zeroed::<u32>("pt-kept", c)?,
            count: gpu.create_buffer("pt-count", 4, MemoryKind::Readback)?,
            compact,
            compact_scratch,
            sorter,
        })
    }
}

/// The path tracer as an [`Integrator`]: the film is the GPU's per-pixel Σ L and Σ L².
pub struct PtIntegrator<'t> {
    gpu: Gpu,
    tracer: Box<dyn Tracer + 't>,
    options: PtOptions,
    pipelines: Pipelines,
    scene: SceneBuffers,
    wave: Wavefront,
    /// Per pixel Σ L (rgb) and samples (w): the film, shared with previews.
    accum: Arc<Buffer>,
    accum2: Buffer,
    /// `finish`'s count of non-finite samples it dropped.
    counters: Buffer,
    params: PtParams,
    pixels: usize,
    /// Whole passes per chunk when the image is small, else one pass in pixel ranges.
    passes_per_chunk: u32,
    pixels_per_chunk: usize,
    nee_on: bool,
    /// The light table on the GPU, as the host last computed it (a new frame uploads it
    /// only where it changed).
    light_table: LightTable,
    passes: u32,
    rays_traced: u64,
}

impl<'t> PtIntegrator<'t> {
    pub fn new(
        gpu: &Gpu,
        tracer: Box<dyn Tracer + 't>,
        scene: &PtScene,
        camera: &CameraFrame,
        options: &PtOptions,
    ) -> vk::Result<Self> {
        let pixels = camera.width as usize * camera.height as usize;
        let max_paths = options.max_paths_per_chunk.max(1) as usize;
        let passes_per_chunk = (max_paths / pixels.max(1)).clamp(1, options.spp.max(1) as usize);
        let pixels_per_chunk = pixels.min(max_paths);
        let chunk = passes_per_chunk * pixels_per_chunk;

        let mut params = PtParams::new(camera);
        params.seed = options.seed as u32 ^ (options.seed >> 32) as u32;
        params.max_depth = options.max_depth;
        params.rr_depth = options.rr_depth;
        params.light_count = scene.lights.lights.len() as u32;
        params.ray_epsilon = scene.ray_epsilon;
        params.brightness_scale = scene.lights.brightness_scale(scene.bounds.radius());
        params.flags = match options.strategy {
            Strategy::Mis => FLAG_NEE | FLAG_BSDF,
            Strategy::Nee => FLAG_NEE,
            Strategy::Bsdf => FLAG_BSDF,
        };
        if options.sort {
            params.flags |= FLAG_SORTED;
        }
        if scene.has_normals() {
            params.flags |= FLAG_NORMALS;
        }
        Ok(Self {
            gpu: gpu.clone(),
            tracer,
            options: *options,
            pipelines: Pipelines::new(gpu, crate::bsdf::layer_kinds(&scene.bsdfs))?,
            scene: SceneBuffers::new(gpu, scene)?,
            wave: Wavefront::new(gpu, chunk, options.sort)?,
            // Sums and their remainders (film_sum.glsl).
            accum: Arc::new(gpu.zeroed::<[f32; 4]>("pt-accum", 2 * pixels)?),
            accum2: gpu.zeroed::<[f32; 4]>("pt-accum2", 2 * pixels)?,
            counters: gpu.zeroed::<u32>("pt-counters", 1)?,
            params,
            pixels,
            passes_per_chunk: passes_per_chunk as u32,
            pixels_per_chunk,
            nee_on: options.strategy != Strategy::Bsdf && !scene.lights.lights.is_empty(),
            light_table: scene.lights.clone(),
            passes: 0,
            rays_traced: 0,
        })
    }

    /// The film so far as [`PtOutput`].
    pub fn output(&self) -> vk::Result<PtOutput> {
        self.gpu.wait_idle()?;
        Ok(PtOutput {
            sum_rgb: self.accum.read()?,
            sum_sq: self.accum2.read()?,
            brightness_scale: self.params.brightness_scale,
            size: [self.params.width, self.params.height],
            passes: self.passes,
            rays_traced: self.rays_traced,
            non_finite_dropped: self.counters.read::<u32>()?[0] as u64,
        })
    }

    /// One chunk: `batch` samples (from `params.sample_index`) of the pixels
    /// `offset..offset + pixel_count`, traced bounce by bounce until every path ended,
    /// then added to the film.
    fn render_chunk(&mut self, offset: usize, pixel_count: u32, batch: u32) -> vk::Result<()> {
        let n0 = pixel_count * batch;
        self.params.pixel_offset = offset as u32;
        self.params.pixel_count = pixel_count;
        self.params.path_count = n0;
        let w = &self.wave;
        let mut rec = self.gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &self.pipelines.generate,
            &[
                (&w.rays[0]).into(),
                (&w.active[0]).into(),
                (&w.paths).into(),
            ],
            &self.params,
            n0 as u64,
        )?;
        let mut ready = rec.submit(&[])?;
        let mut cur = 0usize;
        let mut n = n0;
        let mut bounce = 0u32;
        while n > 0 {
            crate::timeline_counter!("pt", "live paths", n);
            let _bounce = tracing::info_span!("pt bounce", bounce, paths = n).entered();
            self.params.active_count = n;
            self.params.bounce = bounce;
            let survivors = self.bounce(cur, n, &ready)?;
            if survivors == 0 {
                crate::timeline_counter!("pt", "live paths", 0);
                break;
            }
            ready = self.gather_survivors(cur, survivors)?;
            cur = 1 - cur;
            n = survivors;
            bounce += 1;
        }
        let mut rec = self.gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &self.pipelines.finish,
            &[
                (&self.wave.paths).into(),
                (&*self.accum).into(),
                (&self.accum2).into(),
                (&self.counters).into(),
            ],
            &self.params,
            pixel_count as u64,
        )?;
        self.gpu.wait(&rec.submit(&[])?)
    }

    /// One bounce of the `n` live paths in list `cur`: trace, sort, shade, shadow rays,
    /// compaction. Returns how many paths survive.
    fn bounce(&mut self, cur: usize, n: u32, ready: &TimelinePoint) -> vk::Result<u32> {
        let (gpu, w, s, pl) = (&self.gpu, &self.wave, &self.scene, &self.pipelines);
        let params = &self.params;
        let traced = self
            .tracer
            .trace(&w.rays[cur], &w.hits, n, Query::ClosestHit, &[ready])?;
        self.rays_traced += n as u64;

        let mut rec = gpu.recorder(StreamKind::Main)?;
        if let Some(sorter) = &w.sorter {
            sorter.record(&mut rec, n, &w.hits, s, &w.keys, &w.order)?;
        }
        rec.dispatch_items(
            &pl.shade,
            &[
                (&w.rays[cur]).into(),
                (&w.hits).into(),
                (&w.active[cur]).into(),
                (&w.order).into(),
                (&w.paths).into(),
                (&s.triangles).into(),
                (&s.triangle_material).into(),
                (&s.materials).into(),
                (&s.bsdfs).into(),
                (&s.normals).into(),
                (&s.lights).into(),
                (&s.light_cdf).into(),
                (&s.tri_pmf).into(),
                (&w.shadow_rays).into(),
                (&w.nee).into(),
                (&w.alive).into(),
            ],
            params,
            n as u64,
        )?;
        let shaded = rec.submit(&[&traced])?;

        let mut rec = gpu.recorder(StreamKind::Main)?;
        let after = if self.nee_on {
            let occluded = self.tracer.trace(
                &w.shadow_rays,
                &w.shadow_hits,
                n,
                Query::Occlusion,
                &[&shaded],
            )?;
            self.rays_traced += n as u64;
            rec.dispatch_items(
                &pl.nee_accumulate,
                &[
                    (&w.active[cur]).into(),
                    (&w.shadow_hits).into(),
                    (&w.nee).into(),
                    (&w.paths).into(),
                ],
                params,
                n as u64,
            )?;
            occluded
        } else {
            shaded
        };
        w.compact.record(
            &mut rec,
            n,
            (&w.alive).into(),
            Kept::Indices,
            (&w.kept).into(),
            (&w.count).into(),
            &w.compact_scratch,
        )?;
        let done = rec.submit(&[&after])?;
        Ok(w.count.read_after::<u32>(&done)?[0].min(n))
    }

    /// Moves the `survivors` paths' rays and ids of list `cur` to the front of the
    /// other list, in their original order.
    fn gather_survivors(&mut self, cur: usize, survivors: u32) -> vk::Result<TimelinePoint> {
        let w = &self.wave;
        self.params.active_count = survivors;
        let mut rec = self.gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &self.pipelines.gather,
            &[
                (&w.kept).into(),
                (&w.rays[cur]).into(),
                (&w.active[cur]).into(),
                (&w.rays[1 - cur]).into(),
                (&w.active[1 - cur]).into(),
            ],
            &self.params,
            survivors as u64,
        )?;
        rec.submit(&[])
    }
}

impl Integrator for PtIntegrator<'_> {
    fn name(&self) -> &'static str {
        "pt"
    }

    fn passes_per_call(&self) -> u32 {
        self.passes_per_chunk
    }

    fn render_passes(&mut self, first: u32, count: u32) -> Result<(), IntegratorError> {
        let mut done = 0;
        while done < count {
            let batch = self.passes_per_chunk.min(count - done);
            self.params.sample_index = first + done;
            for offset in (0..self.pixels).step_by(self.pixels_per_chunk) {
                let pixel_count = self.pixels_per_chunk.min(self.pixels - offset) as u32;
                self.render_chunk(offset, pixel_count, batch)?;
            }
            done += batch;
        }
        self.passes += count;
        Ok(())
    }

    fn sums(&mut self) -> Result<FilmSums, IntegratorError> {
        Ok(self.output()?.sums())
    }

    fn restore(&mut self, sums: &FilmSums) -> Result<(), IntegratorError> {
        check_film_size(sums, self.params.width, self.params.height, 1)?;
        let (sum, sum_sq) = sums.to_gpu(self.params.brightness_scale);
        let zeros = vec![[0.0f32; 4]; 2 * self.pixels];
        self.accum.write(&sum)?;
        self.accum2.write(sum_sq.as_deref().unwrap_or(&zeros))?;
        self.passes = sums.passes;
        Ok(())
    }

    fn stats(&self) -> IntegratorStats {
        // The count is a diagnostic: a device that cannot be read leaves it out.
        let dropped = self.counters.read::<u32>().map(|c| c[0] as u64);
        let counters: Vec<_> = dropped.iter().map(|&n| ("non_finite_dropped", n)).collect();
        IntegratorStats::with_counters(self.rays_traced, &counters)
    }

    fn set_frame(&mut self, frame: &SceneFrame<'_>) -> Result<(), IntegratorError> {
        if (frame.camera.width, frame.camera.height) != (self.params.width, self.params.height) {
            return Err(IntegratorError::Usage(
                "a frame cannot change the film size".to_string(),
            ));
        }
        Ok(self.move_to_frame(frame)?)
    }

    fn device_film(&self) -> Option<DeviceFilm> {
        Some(DeviceFilm {
            sums: self.accum.clone(),
            width: self.params.width,
            height: self.params.height,
        })
    }

    /// Material sorting is not among them: it never changes the image
    /// (tests/suite/pt_analytic.rs), so parts rendered with it and without (on devices whose
    /// defaults differ) merge.
    fn settings(&self) -> Vec<(String, String)> {
        let o = &self.options;
        vec![
            ("max_depth".into(), o.max_depth.to_string()),
            ("rr_depth".into(), o.rr_depth.to_string()),
            (
                "strategy".into(),
                format!("{:?}", o.strategy).to_lowercase(),
            ),
        ]
    }
}

/// Renders passes until `options.spp` are done or `options.time_limit` ran out;
/// `progress` is called with the number of passes done. (The render loop of
/// `crate::render` does the same for every integrator; this is the path tracer alone,
/// for tests and benchmarks.)
pub fn render_pt(
    gpu: &Gpu,
    tracer: &mut dyn Tracer,
    scene: &PtScene,
    camera: &CameraFrame,
    options: &PtOptions,
    progress: &mut dyn FnMut(u32),
) -> vk::Result<PtOutput> {
    let start = Instant::now();
    let mut pt = PtIntegrator::new(
        gpu,
        Box::new(BorrowedTracer(tracer)),
        scene,
        camera,
        options,
    )?;
    while pt.passes < options.spp {
        let batch = pt.passes_per_chunk.min(options.spp - pt.passes);
        pt.render_passes(pt.passes, batch).map_err(|e| match e {
            IntegratorError::Gpu(e) => e,
            IntegratorError::Usage(m) => vk::VkError::Usage(m),
        })?;
        progress(pt.passes);
        if options
            .time_limit
            .is_some_and(|limit| start.elapsed().as_secs_f64() >= limit)
        {
            break;
        }
    }
    pt.output()
}

/// A tracer lent to an integrator that owns its tracer.
struct BorrowedTracer<'a>(&'a mut dyn Tracer);

impl Tracer for BorrowedTracer<'_> {
    fn name(&self) -> &'static str {
        self.0.name()
    }
    fn set_geometry(&mut self, triangles: &[crate::trace::GpuTriangle]) -> vk::Result<()> {
        self.0.set_geometry(triangles)
    }
    fn update_geometry(
        &mut self,
        triangles: &[crate::trace::GpuTriangle],
        changed: &[std::ops::Range<usize>],
    ) -> vk::Result<()> {
        self.0.update_geometry(triangles, changed)
    }
    fn trace(
        &mut self,
        rays: &Buffer,
        hits: &Buffer,
        ray_count: u32,
        query: Query,
        after: &[&TimelinePoint],
    ) -> vk::Result<TimelinePoint> {
        self.0.trace(rays, hits, ray_count, query, after)
    }
    fn level_stats(&self) -> Option<&crate::trace::pdacrt::TraceStats> {
        self.0.level_stats()
    }
}
