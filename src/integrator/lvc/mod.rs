//! `lvc-bdpt` and `cis-lbdpt`: bidirectional path tracing with a light vertex cache on
//! the GPU (Davidovič et al. 2014, "Progressive light transport simulation on the GPU";
//! thesis ch. 4, Algorithms 7 and 8), on the [`Tracer`] interface (PDACRT by default).
//!
//! A pass gives every pixel one camera subpath and makes N_L light subpaths (one per
//! pixel by default). Per chunk of passes:
//!
//! 1. **light pass** ([`light_pass`], Algorithm 7): the light subpaths as a wavefront;
//!    every connectible surface vertex goes to the light vertex cache ([`cache`]), sized
//!    by a prepass ([`plan`]), never dropping a vertex (grow and redo);
//! 2. **light tracing** ([`light_tracing`], t = 1): every cached vertex connected to
//!    the camera, splatted in fixed point ([`fixed`]) so that the sums are the same in
//!    any order;
//! 3. **camera pass** ([`camera_pass`], Algorithm 8): per bounce, emitter hits (s = 0),
//!    then direct lighting (s = 1), connections (s, t ≥ 2) and the next bounce as three
//!    kernels on three streams ordered by timeline semaphores, their shadow rays traced
//!    together.
//!
//! Connections go to N cache vertices of the camera path's own pass: drawn uniformly
//! (LVC-BDPT) or resampled from M candidates in proportion to their unoccluded
//! contribution (CIS-LBDPT, Talbot et al. 2005's resampled importance sampling; see
//! `camera_connect.comp`). The balance heuristic weighs every technique with Veach's
//! sample counts ([`crate::bidir::mis`]): the emitter hit and direct lighting once, light
//! tracing N_L times, and a connection to a vertex of the cache as if it were a sample of
//! count N N_L / E|C| = N / v̄ — the expected number of connections to vertices of one
//! light path ([`lvc_counts`]). v̄, the mean cached vertices per light path, comes from the
//! prepass on light paths of their own, so the weights are a function of the path alone:
//! they sum to 1 over a path's techniques and the image is unbiased. The vertices, the
//! throughputs and the recursive MIS quantities are those of the CPU `bpt`'s walks and
//! connections ([`crate::bidir`]), which are the CPU twins of the kernels (`twin`).
//!
//! **Determinism.** Random numbers are a function of (pixel or light path, pass,
//! dimension, seed): the camera and light subpaths of pass k are `bpt`'s of pass k.
//! Every kernel writes by the item's place in the unsorted active list, the cache's
//! content and index do not depend on scheduling, and splats are sums of integers, so the
//! image is the same bit for bit with sorting on or off, with one stream or three, and
//! however passes are grouped into calls.

pub mod cache;
pub mod camera_pass;
pub mod fixed;
mod frame;
pub mod gpu;
pub mod kernels;
pub mod light_pass;
pub mod light_tracing;
pub mod observe;
pub mod options;
pub mod plan;
mod techniques;
pub mod twin;
pub mod wavefront;

use crate::bidir::mis::TechniqueCounts;
use crate::bidir::random::fold_seed;
use crate::film::FilmSums;
use crate::integrator::pt::{LightTable, PtScene, SceneBuffers};
use crate::integrator::{
    check_film_size, Integrator, IntegratorError, IntegratorStats, NamedImage, SceneFrame,
};
use crate::scene::{Aabb, CameraFrame};
use crate::trace::Tracer;
use crate::vk::{self, Buffer, Gpu, Recorder};

use self::cache::LightCache;
pub use self::camera_pass::Visibility;
use self::camera_pass::{trace_camera_paths, CameraRange, CameraTargets, Streams};
use self::gpu::{LvcConstants, FLAG_NORMALS, FLAG_SORTED, FLAG_SYSTEMATIC};
use self::kernels::Kernels;
use self::light_pass::trace_light_paths;
use self::light_tracing::splat_cache;
pub use self::observe::{ChunkView, NoObserver, Observer};
pub use self::options::{Families, LvcOptions, Resampling, Variant};
use self::plan::{prepass_paths, Plan, PREPASS_SAMPLE};
use self::techniques::TechniqueRecorder;
use self::wavefront::Wavefront;

/// The technique counts of a render with `connections` per camera vertex, `light_paths`
/// per pass and `per_path` cached vertices per light path on average (see the module
/// docs); families turned off get count 0.
pub fn lvc_counts(
    families: &Families,
    connections: u32,
    light_paths: u32,
    per_path: f64,
) -> TechniqueCounts {
    let on = |f: bool, n: f32| if f { n } else { 0.0 };
    TechniqueCounts {
        emitter_hit: on(families.emitter_hit, 1.0),
        light_sample: on(families.light_sample, 1.0),
        connection: on(
            families.connection,
            (connections as f64 / per_path.max(1e-6)) as f32,
        ),
        light_trace: on(families.light_trace, light_paths as f32),
        light_trace_emitter: 0.0,
    }
}

/// The constants of a render through `camera` before its prepass: the camera, the
/// scene's `ray_epsilon` ([`Aabb::ray_epsilon`] from the camera and the point lights),
/// the splat film's scale from the scene's `bounds` and `lights`, the light count, N_L
/// of the plan before the prepass fits it, and provisional counts (the prepass's
/// vertices do not depend on them). The caller adds [`FLAG_NORMALS`] where the scene
/// has shading normals.
fn prepass_constants(
    options: &LvcOptions,
    plan: &Plan,
    camera: &CameraFrame,
    bounds: &Aabb,
    ray_epsilon: f32,
    lights: &LightTable,
) -> LvcConstants {
    let mut constants = LvcConstants::new(camera);
    constants.ray_epsilon = ray_epsilon;
    constants.brightness_scale = lights.brightness_scale(bounds.radius());
    constants.seed = fold_seed(options.seed);
    constants.light_paths = plan.light_paths;
    constants.max_depth = options.max_depth;
    constants.rr_depth = options.rr_depth;
    constants.light_count = lights.lights.len() as u32;
    constants.connections = options.connections;
    constants.candidates = options.candidates;
    constants.flags = if options.sort { FLAG_SORTED } else { 0 }
        | match options.resampling {
            Resampling::Independent => 0,
            Resampling::Systematic => FLAG_SYSTEMATIC,
        };
    constants.set_counts(&lvc_counts(
        &options.families,
        options.connections,
        plan.light_paths,
        1.0,
    ));
    constants
}

/// Whether material sorting pays on `gpu`, as measured (docs/PERFORMANCE.md). The
/// thesis sorts because divergent material evaluation serialises SIMT groups (§4.2.2,
/// §4.5.1), so sorting is the default on GPUs — except where measurements say
/// otherwise: on CPU implementations (lavapipe) sorting is pure overhead (as for `pt`,
/// whose rule this starts from), and on NVIDIA's driver (an H200) every built-in scene
/// renders 0–13 % slower sorted, both integrators, one stream or three (tracing rules a
/// pass there; material evaluation is too small a share for coherence to win the sort
/// back). `--sort` still turns it on.
pub fn sort_pays(gpu: &Gpu) -> bool {
    super::pt::sort_pays(gpu) && gpu.info().driver_name != "NVIDIA"
}

/// The [`Shared`] view of an [`LvcIntegrator`]'s fields, borrowed field by field so
/// that its tracer can be borrowed mutably beside it.
macro_rules! shared {
    ($s:expr) => {
        Shared {
            gpu: &$s.gpu,
            kernels: &$s.kernels,
            scene: &$s.scene,
            constants: &$s.constants_buffer,
            wave: &$s.wave,
            cache: &$s.cache,
            connections: $s.options.connections,
        }
    };
}

/// The parts of the integrator every stage reads.
pub struct Shared<'a> {
    pub gpu: &'a Gpu,
    pub kernels: &'a Kernels,
    pub scene: &'a SceneBuffers,
    pub constants: &'a Buffer,
    pub wave: &'a Wavefront,
    pub cache: &'a LightCache,
    /// N.
    pub connections: u32,
}

impl Shared<'_> {
    /// Records the material sort of the first `n` live paths' hits (when sorting is on):
    /// keys (type << 24 | id, misses last) and the ids that the shading kernels read
    /// their items through. Ids move; ray data stays.
    pub fn record_sort(&self, rec: &mut Recorder, n: u32) -> vk::Result<()> {
        let w = self.wave;
        match &w.sorter {
            Some(sorter) => sorter.record(rec, n, &w.hits, self.scene, &w.keys, &w.order),
            None => Ok(()),
        }
    }
}

/// Figures counted while rendering.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LvcCounters {
    pub light_paths: u64,
    pub camera_paths: u64,
    pub cache_vertices: u64,
    pub rays: u64,
    /// Shadow-ray slots of the camera passes handed to the tracer, empty ones included
    /// (`shadow_ray_slots` in the stats; [`Visibility`] counts the rays that carried a
    /// contribution).
    pub shadow_rays: u64,
    pub cache_regrowths: u64,
    /// The camera passes' shadow rays that carried a contribution, and the unoccluded.
    pub visibility: Visibility,
}

/// LVC-BDPT or CIS-LBDPT as an [`Integrator`].
pub struct LvcIntegrator<'t> {
    gpu: Gpu,
    tracer: Box<dyn Tracer + 't>,
    options: LvcOptions,
    kernels: Kernels,
    scene: SceneBuffers,
    /// The light table on the GPU, as the host last computed it (a new frame uploads it
    /// only where it changed).
    light_table: LightTable,
    constants: LvcConstants,
    constants_buffer: Buffer,
    wave: Wavefront,
    cache: LightCache,
    plan: Plan,
    /// v̄: mean cached vertices per light path (prepass).
    per_path: f64,
    splat_film: Buffer,
    accum: Buffer,
    accum2: Buffer,
    counters_buffer: Buffer,
    counters: LvcCounters,
    techniques: Option<TechniqueRecorder>,
    passes: u32,
}

impl<'t> LvcIntegrator<'t> {
    pub fn new(
        gpu: &Gpu,
        tracer: Box<dyn Tracer + 't>,
        scene: &PtScene,
        camera: &CameraFrame,
        options: &LvcOptions,
    ) -> Result<Self, IntegratorError> {
        options.check()?;
        let plan = Plan::new(gpu, camera.width, camera.height, options);
        let mut constants = prepass_constants(
            options,
            &plan,
            camera,
            &scene.bounds,
            scene.ray_epsilon,
            &scene.lights,
        );
        if scene.has_normals() {
            constants.flags |= FLAG_NORMALS;
        }
        let pixels = plan.pixels as usize;
        let max_light_paths = plan.chunk_light_paths(plan.passes_per_chunk);
        let mut integrator = Self {
            gpu: gpu.clone(),
            tracer,
            options: *options,
            kernels: Kernels::new(gpu, options, crate::bsdf::layer_kinds(&scene.bsdfs))?,
            scene: SceneBuffers::new(gpu, scene)?,
            light_table: scene.lights.clone(),
            constants_buffer: gpu.upload("lvc-constants", &[constants])?,
            constants,
            wave: Wavefront::new(gpu, plan.wave_capacity, options.connections, options.sort)?,
            cache: LightCache::new(gpu, 1, max_light_paths)?,
            plan,
            per_path: 1.0,
            splat_film: gpu.zeroed::<u32>(
                "lvc-splat-film",
                plan.passes_per_chunk as usize * pixels * fixed::FIXED_WORDS,
            )?,
            // Sums and their remainders (film_sum.glsl).
            accum: gpu.zeroed::<[f32; 4]>("lvc-accum", 2 * pixels)?,
            accum2: gpu.zeroed::<[f32; 4]>("lvc-accum2", 2 * pixels)?,
            counters_buffer: gpu.zeroed::<u32>("lvc-counters", gpu::COUNTERS)?,
            counters: LvcCounters::default(),
            techniques: options
                .technique_images
                .then(|| TechniqueRecorder::new(camera.width, camera.height)),
            passes: 0,
        };
        integrator.prepass()?;
        Ok(integrator)
    }

    /// Measures v̄ on light paths of their own and sizes the cache and the counts (from
    /// the plan and constants of [`Plan::new`] and [`prepass_constants`], on the GPU).
    fn prepass(&mut self) -> Result<(), IntegratorError> {
        let _span = tracing::info_span!("lvc prepass").entered();
        let paths = prepass_paths(self.plan.light_paths);
        let outcome = {
            let shared = shared!(self);
            trace_light_paths(
                &shared,
                self.tracer.as_mut(),
                &self.cache,
                PREPASS_SAMPLE,
                paths,
            )?
        };
        self.counters.rays += outcome.rays;
        // At least one vertex in all: a count factor stays finite when the prepass found
        // none (any fixed positive count keeps the weights summing to 1).
        self.per_path = (outcome.vertices.max(1)) as f64 / paths as f64;
        self.plan.fit_cache(&self.gpu, self.per_path);
        self.constants.light_paths = self.plan.light_paths;
        self.constants.set_counts(&lvc_counts(
            &self.options.families,
            self.options.connections,
            self.plan.light_paths,
            self.per_path,
        ));
        self.constants_buffer.write(&[self.constants])?;
        let capacity = match self.options.initial_cache {
            Some(c) => c as u64,
            None => self.plan.cache_capacity(self.per_path),
        };
        self.gpu.wait_idle()?;
        self.cache.set_capacity(&self.gpu, capacity)?;
        Ok(())
    }

    /// The technique counts of the balance heuristic.
    pub fn counts(&self) -> TechniqueCounts {
        self.constants.counts()
    }

    /// v̄, the mean cached vertices per light path measured by the prepass.
    pub fn vertices_per_path(&self) -> f64 {
        self.per_path
    }

    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    pub fn constants(&self) -> &LvcConstants {
        &self.constants
    }

    pub fn lvc_counters(&self) -> LvcCounters {
        self.counters
    }

    /// The kernels' counts: non-finite contributions dropped, splat parts clamped.
    pub fn kernel_counters(&self) -> vk::Result<[u32; gpu::COUNTERS]> {
        let c = self.counters_buffer.read::<u32>()?;
        Ok([c[0], c[1]])
    }

    /// Renders passes `first..first + count` as [`Integrator::render_passes`] does,
    /// showing `observer` what each chunk leaves in the GPU's buffers.
    pub fn render_observed(
        &mut self,
        first: u32,
        count: u32,
        observer: &mut dyn Observer,
    ) -> Result<(), IntegratorError> {
        let _span = tracing::info_span!("lvc passes", first, count).entered();
        let mut done = 0;
        while done < count {
            let passes = self.plan.passes_per_chunk.min(count - done);
            self.render_chunk(first + done, passes, observer)?;
            done += passes;
        }
        self.passes += count;
        Ok(())
    }

    /// One chunk: passes `first..first + passes`.
    fn render_chunk(
        &mut self,
        first: u32,
        passes: u32,
        observer: &mut dyn Observer,
    ) -> Result<(), IntegratorError> {
        let light_paths = self.plan.chunk_light_paths(passes);
        let outcome = loop {
            let shared = shared!(self);
            let outcome = trace_light_paths(
                &shared,
                self.tracer.as_mut(),
                &self.cache,
                first,
                light_paths,
            )?;
            self.counters.rays += outcome.rays;
            if outcome.fits(&self.cache) {
                break outcome;
            }
            // Too many vertices for the cache: grow it and run the light pass again.
            self.counters.cache_regrowths += 1;
            self.gpu.wait_idle()?;
            self.cache.grow(&self.gpu, outcome.vertices)?;
        };
        self.counters.light_paths += light_paths as u64;
        self.counters.cache_vertices += outcome.vertices;
        let chunk = ChunkView {
            first_pass: first,
            passes,
            light_paths,
            vertices: outcome.vertices as u32,
        };
        let pixels = self.plan.pixels as u64;
        {
            let mut rec = self.gpu.recorder(vk::StreamKind::Main)?;
            let words = passes as u64 * pixels * fixed::FIXED_WORDS as u64 * 4;
            rec.fill_range(&self.splat_film, 0, words, 0)?;
            self.gpu.wait(&rec.submit(&[])?)?;
        }
        let shared = shared!(self);
        observer.light_pass(&shared, &chunk)?;
        let tracer = self.tracer.as_mut();
        let (splat_film, counters) = (&self.splat_film, &self.counters_buffer);
        self.counters.rays += splat_cache(
            &shared,
            tracer,
            chunk.vertices,
            splat_film,
            counters,
            &mut |s, batch| observer.splats(s, &chunk, batch),
        )?;
        observer.splat_film(splat_film, &chunk)?;
        let targets = CameraTargets {
            splat_film,
            accum: &self.accum,
            accum2: &self.accum2,
            counters,
        };
        let streams = Streams::new(self.options.streams);
        let (total, step) = (self.plan.pixels, self.plan.pixels_per_chunk);
        let mut offset = 0;
        while offset < total {
            let count = step.min(total - offset);
            let camera = trace_camera_paths(
                &shared,
                tracer,
                streams,
                &targets,
                CameraRange {
                    first_pass: first,
                    passes,
                    pixel_offset: offset,
                    pixel_count: count,
                },
                &mut |s, view| observer.bounce(s, &chunk, view),
            )?;
            self.counters.camera_paths += (passes * count) as u64;
            self.counters.rays += camera.rays + camera.shadow_rays;
            self.counters.shadow_rays += camera.shadow_rays;
            self.counters.visibility.merge(&camera.visibility);
            offset += count;
        }
        observer.end_chunk(&chunk);
        Ok(())
    }
}

impl Integrator for LvcIntegrator<'_> {
    fn name(&self) -> &'static str {
        self.options.variant.name()
    }

    fn passes_per_call(&self) -> u32 {
        self.plan.passes_per_chunk
    }

    fn render_passes(&mut self, first: u32, count: u32) -> Result<(), IntegratorError> {
        let mut techniques = self.techniques.take();
        let result = match &mut techniques {
            Some(t) => self.render_observed(first, count, t),
            None => self.render_observed(first, count, &mut NoObserver),
        };
        self.techniques = techniques;
        result
    }

    fn sums(&mut self) -> Result<FilmSums, IntegratorError> {
        self.gpu.wait_idle()?;
        let sum: Vec<[f32; 4]> = self.accum.read()?;
        let sum_sq: Vec<[f32; 4]> = self.accum2.read()?;
        Ok(FilmSums::from_gpu(
            self.constants.width,
            self.constants.height,
            self.passes,
            1,
            &sum,
            Some(&sum_sq),
            self.constants.brightness_scale,
        ))
    }

    fn restore(&mut self, sums: &FilmSums) -> Result<(), IntegratorError> {
        check_film_size(sums, self.constants.width, self.constants.height, 1)?;
        let (sum, sum_sq) = sums.to_gpu(self.constants.brightness_scale);
        let zeros = vec![[0.0f32; 4]; 2 * self.plan.pixels as usize];
        self.gpu.wait_idle()?;
        self.accum.write(&sum)?;
        self.accum2.write(sum_sq.as_deref().unwrap_or(&zeros))?;
        self.passes = sums.passes;
        if let Some(t) = &mut self.techniques {
            t.clear();
        }
        Ok(())
    }

    fn stats(&self) -> IntegratorStats {
        let c = &self.counters;
        let kernel = self.kernel_counters().unwrap_or_default();
        let counters = [
            ("light_paths", c.light_paths),
            ("camera_paths", c.camera_paths),
            ("cache_vertices", c.cache_vertices),
            ("shadow_ray_slots", c.shadow_rays),
            ("cache_regrowths", c.cache_regrowths),
            ("direct_shadow_rays", c.visibility.direct_rays),
            ("direct_unoccluded", c.visibility.direct_unoccluded),
            ("connection_shadow_rays", c.visibility.connection_rays),
            (
                "connections_unoccluded",
                c.visibility.connections_unoccluded,
            ),
            ("non_finite_dropped", kernel[gpu::COUNTER_NON_FINITE] as u64),
            ("splats_clamped", kernel[gpu::COUNTER_CLAMPED] as u64),
        ];
        IntegratorStats::with_counters(c.rays, &counters)
    }

    fn settings(&self) -> Vec<(String, String)> {
        let o = &self.options;
        let n = self.counts();
        let mut s = vec![
            ("max_depth".into(), o.max_depth.to_string()),
            ("rr_depth".into(), o.rr_depth.to_string()),
            ("connections".into(), o.connections.to_string()),
            (
                "light_paths_per_pass".into(),
                self.plan.light_paths.to_string(),
            ),
            (
                "light_vertices_per_path".into(),
                format!("{:.6}", self.per_path),
            ),
            (
                "technique_counts".into(),
                format!(
                    "hit {} nee {} connect {} trace {}",
                    n.emitter_hit, n.light_sample, n.connection, n.light_trace
                ),
            ),
        ];
        if o.variant == Variant::CisLbdpt {
            s.push(("candidates".into(), o.candidates.to_string()));
            s.push(("resampling".into(), o.resampling.name().into()));
        }
        s
    }

    fn extra_images(&mut self) -> Result<Vec<NamedImage>, IntegratorError> {
        Ok(self
            .techniques
            .as_ref()
            .map(|t| t.images())
            .unwrap_or_default())
    }

    fn set_frame(&mut self, frame: &SceneFrame<'_>) -> Result<(), IntegratorError> {
        let c = &self.constants;
        if (frame.camera.width, frame.camera.height) != (c.width, c.height) {
            return Err(IntegratorError::Usage(
                "a frame cannot change the film size".to_string(),
            ));
        }
        self.move_to_frame(frame)
    }
}
