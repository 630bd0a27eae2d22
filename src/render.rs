//! A render from start to finish: scene → GPU data → tracer → AOVs → integrator passes
//! → film, with the statistics a user profiles by. The pass loop is the same for every
//! integrator (`run_passes`); a [`RenderPlan`] makes it continue a [`Checkpoint`],
//! take one [`Shard`]'s passes, or save its film as it goes.

pub mod checkpoint;
pub mod device_fit;
pub mod fingerprint;
pub mod frames;
pub mod merge;
pub mod part;
mod plan;
pub mod shard;
mod watch;

use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use crate::film::{self, Film, FilmError, FilmSums, RenderMetadata};
use crate::integrator::{
    self, aov, EyeInputs, EyeIntegrator, EyeOptions, GpuMaterial, Integrator, IntegratorError,
    IntegratorKind, IntegratorStats, NamedImage,
};
use crate::scene::validate::{is_film_side, MAX_FILM_DIM};
use crate::scene::{CameraFrame, Scene, SceneError};
use crate::trace::{GpuTriangle, Tracer, TracerKind};
use crate::vk::{self, Gpu, KernelTime, ProfileTree};
pub use checkpoint::Checkpoint;
pub use fingerprint::Fingerprint;
pub use part::PartRecord;
use plan::start_film;
pub use plan::{CheckpointHook, FilmSnapshot, RenderPlan, Resume};
pub use shard::{PassRanges, Shard};
pub use watch::{FilmWatch, WatchStart};

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Scene(#[from] Box<SceneError>),
    #[error(transparent)]
    Gpu(#[from] vk::VkError),
    #[error(transparent)]
    Film(#[from] FilmError),
    #[error(transparent)]
    Integrator(#[from] IntegratorError),
    #[error("{0}")]
    Options(String),
    /// A checkpoint or image part that cannot be used, and why.
    #[error("{}: {message}", .path.display())]
    BadFile { path: PathBuf, message: String },
}

impl From<SceneError> for RenderError {
    fn from(e: SceneError) -> Self {
        Self::Scene(Box::new(e))
    }
}

/// Everything that decides the image besides the scene.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u64,
    pub integrator: IntegratorKind,
    pub tracer: TracerKind,
    pub ao_rays: u32,
    /// Every integrator that follows paths (`pt`, `bpt`, `light`, `lvc-bdpt`,
    /// `cis-lbdpt`, `cbpt`): Mitsuba's max_depth (1 = emitters seen directly, 2 = direct
    /// light; < 0 unbounded). From the scene's `[render] max_depth`, else unbounded.
    pub max_depth: i32,
    /// The same integrators: Russian roulette from this depth on (Mitsuba's default 5).
    pub rr_depth: u32,
    /// `pt`: sort paths by material key before shading; `None`: where it pays on the
    /// device (`pt::sort_pays`). The cache integrators' setting is `lvc.sort`.
    pub sort_materials: Option<bool>,
    /// `pt`: which estimators contribute light.
    pub strategy: integrator::pt::Strategy,
    /// Stop after the pass during which this many seconds ran out (`spp` is then the
    /// most passes).
    pub time_limit: Option<f64>,
    /// A reference image of this film's size: the render reports its relative MSE
    /// against it as it goes.
    pub reference: Option<std::sync::Arc<film::Reference>>,
    /// `bpt`, `light`, `lvc-bdpt`, `cis-lbdpt`: keep one image per technique (s, t)
    /// ([`Integrator::extra_images`]).
    pub bdpt_techniques: bool,
    /// `lvc-bdpt`, `cis-lbdpt`: connections, candidates, resampling, streams, sorting.
    pub lvc: integrator::lvc::options::LvcSettings,
    /// `cbpt`: population sizes, batch size, where the combination runs.
    pub cbpt: integrator::cbpt::CbptSettings,
}

impl RenderOptions {
    /// The scene's own settings, overridden by whatever the caller gives.
    pub fn resolve(
        scene: &Scene,
        width: Option<u32>,
        height: Option<u32>,
        spp: Option<u32>,
        seed: Option<u64>,
        integrator: Option<IntegratorKind>,
        tracer: Option<TracerKind>,
    ) -> Result<Self, RenderError> {
        let s = &scene.settings;
        let integrator = match (integrator, &s.integrator) {
            (Some(i), _) => i,
            (None, Some(name)) => name
                .parse()
                .map_err(|e| RenderError::Options(format!("scene '{}': {e}", scene.name)))?,
            (None, None) => IntegratorKind::default(),
        };
        let tracer = match (tracer, &s.tracer) {
            (Some(t), _) => t,
            (None, Some(name)) => name
                .parse()
                .map_err(|e| RenderError::Options(format!("scene '{}': {e}", scene.name)))?,
            (None, None) => TracerKind::default(),
        };
        let options = Self {
            width: width.unwrap_or(scene.film.width),
            height: height.unwrap_or(scene.film.height),
            spp: spp.or(s.spp).unwrap_or(1),
            seed: seed.or(s.seed).unwrap_or(0),
            integrator,
            tracer,
            ao_rays: 8,
            max_depth: s.max_depth.map_or(-1, |d| d.min(i32::MAX as u32) as i32),
            rr_depth: 5,
            sort_materials: None,
            strategy: Default::default(),
            time_limit: None,
            reference: None,
            bdpt_techniques: false,
            lvc: Default::default(),
            cbpt: Default::default(),
        };
        if !is_film_side(options.width) || !is_film_side(options.height) {
            return Err(RenderError::Options(format!(
                "film size {}x{} is outside 1..={MAX_FILM_DIM}",
                options.width, options.height
            )));
        }
        if options.spp == 0 {
            return Err(RenderError::Options("--spp must be at least 1".into()));
        }
        Ok(options)
    }
}

/// Figures of one render, written by `--stats`.
#[derive(Clone, Debug, Serialize)]
pub struct RenderStats {
    pub scene: String,
    pub triangles: usize,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel reached.
    pub spp: u64,
    /// Passes rendered (each adds `spp / passes` samples per pixel).
    pub passes: u32,
    pub seed: u64,
    pub integrator: String,
    pub tracer: String,
    pub device: String,
    pub render_time_s: f64,
    /// Pixel samples per second: spp × pixels / render time.
    pub samples_per_second: f64,
    pub rays_traced: u64,
    pub rays_per_second: f64,
    pub peak_gpu_bytes: u64,
    /// The render stopped before its spp or time limit (a signal, a closed window).
    pub stopped_early: bool,
    /// Relative MSE against `--reference`, at the end of the render.
    pub relative_mse: Option<f64>,
    /// `relative_mse` less the reference's own noise, where its standard errors are
    /// known ([`film::Reference`]).
    pub relative_mse_excess: Option<f64>,
    /// The integrator's own counts (paths, connections, non-finite samples …).
    pub counters: std::collections::BTreeMap<String, u64>,
    /// GPU time per kernel (timestamp queries), longest first.
    pub kernels: Vec<KernelTime>,
    /// The GPU scopes as a tree: a node's total is its self time plus its children's
    /// totals.
    pub profile: ProfileTree,
}

pub struct RenderOutput {
    pub film: Film,
    /// The film's sums (mean and standard error), for checkpoints and merging.
    pub sums: FilmSums,
    /// The scene and settings it was rendered from, and the passes it holds (also in
    /// `metadata`'s header entries).
    pub record: PartRecord,
    /// Global index of the film's first pass.
    pub first_pass: u32,
    /// Seconds spent rendering the film, resumed runs included.
    pub total_render_time_s: f64,
    pub metadata: RenderMetadata,
    pub stats: RenderStats,
    /// Images the integrator was asked for besides the render (technique images …).
    pub extra_images: Vec<NamedImage>,
}

/// How far a render has come, told after every batch of passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    pub passes: u32,
    /// Samples per pixel so far.
    pub spp: u64,
    /// Samples per pixel asked for (`u64::MAX`-like when only a time limit bounds it).
    pub target_spp: u64,
    pub elapsed_s: f64,
    pub time_limit: Option<f64>,
    /// Relative MSE against the reference, when one was given.
    pub relative_mse: Option<f64>,
}

impl RenderOutput {
    /// The finished film as a [`FilmSnapshot`], e.g. for a last checkpoint.
    pub fn snapshot(&self) -> FilmSnapshot<'_> {
        FilmSnapshot {
            sums: &self.sums,
            fingerprint: &self.record.fingerprint,
            shard: self.record.shard.unwrap_or_default(),
            first_pass: self.first_pass,
            render_time_s: self.total_render_time_s,
        }
    }
}

/// What a caller can do while a render runs.
pub struct RenderControl<'a> {
    /// Told after every batch of passes.
    pub progress: &'a mut dyn FnMut(&Progress),
    /// Asked before every batch: `true` stops the render at that pass boundary (the
    /// image then holds the passes done).
    pub stop: &'a dyn Fn() -> bool,
    /// Asked within a pass that is long work in parts ([`Integrator::render_passes_or_abandon`]):
    /// `true` gives the pass up, and the render stops at the boundary before it. A stop
    /// that cannot wait for a whole pass (a signal) answers both; `&|| false` lets every
    /// pass finish.
    pub abandon: &'a dyn Fn() -> bool,
}

/// A one-line description of the device for logs and file headers.
pub fn device_description(gpu: &Gpu) -> String {
    let info = gpu.info();
    format!("{} ({} {})", info.name, info.driver_name, info.driver_info)
}

/// Renders `scene`; `progress` is told how far it has come after every batch of passes.
pub fn render(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<RenderOutput, RenderError> {
    render_with(
        gpu,
        scene,
        options,
        RenderControl {
            progress,
            stop: &|| false,
            abandon: &|| false,
        },
    )
}

/// [`render`] with every control: scene → tracer → AOVs → integrator passes → film.
pub fn render_with(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
    control: RenderControl<'_>,
) -> Result<RenderOutput, RenderError> {
    render_from(gpu, scene, options, RenderPlan::default(), control)
}

/// [`render_with`] following `plan`: a shard's passes, continuing a checkpoint, saving
/// the film as it goes.
pub fn render_from(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
    plan: RenderPlan<'_>,
    control: RenderControl<'_>,
) -> Result<RenderOutput, RenderError> {
    device_fit::check(gpu, scene, options)?;
    let triangles = scene.gpu_triangles();
    let camera = scene.camera.frame(options.width, options.height);

    let start = start_measuring(gpu)?;
    let mut tracer = options.tracer.create(gpu, &triangles)?;
    let aovs = {
        let triangle_buffer = gpu.upload("aov-triangles", &triangles)?;
        aov::render_aovs(gpu, tracer.as_mut(), &triangle_buffer, &camera)?
    };
    let mut integrator = integrator_on(gpu, scene, options, &triangles, tracer)?;
    warn_if_spp_rounds_up(options, integrator.as_ref());
    render_prepared(
        gpu,
        scene,
        options,
        Prepared {
            integrator: integrator.as_mut(),
            aovs,
            start,
            stats_before: IntegratorStats::default(),
        },
        plan,
        control,
    )
}

/// Waits for the device's earlier work and clears its profile and peak memory, so that a
/// render's figures are its own; returns when the render starts.
fn start_measuring(gpu: &Gpu) -> Result<Instant, RenderError> {
    gpu.wait_idle()?;
    let _ = gpu.take_profile();
    gpu.reset_peak_memory();
    Ok(Instant::now())
}

/// An integrator ready for passes, with the render's AOVs.
struct Prepared<'i> {
    integrator: &'i mut dyn Integrator,
    aovs: aov::Aovs,
    /// When the render started (its time includes what was done before the passes).
    start: Instant,
    /// The integrator's counts before this render (an animation's earlier frames).
    stats_before: IntegratorStats,
}

/// The passes of a prepared render following `plan`, and the output they make: the
/// film with its AOVs, statistics, metadata.
fn render_prepared(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
    prepared: Prepared<'_>,
    mut plan: RenderPlan<'_>,
    control: RenderControl<'_>,
) -> Result<RenderOutput, RenderError> {
    let Prepared {
        integrator,
        aovs,
        start,
        stats_before,
    } = prepared;
    let fingerprint = fingerprint_of(scene, options, integrator);
    let (first_pass, resumed_passes) = start_film(integrator, options, &plan, &fingerprint)?;
    if let Some(watch) = plan.watch.as_deref_mut() {
        watch.start(&WatchStart {
            width: options.width,
            height: options.height,
            aovs: &aovs,
            device_film: integrator.device_film(),
            spp: resumed_passes as u64 * integrator.samples_per_pass() as u64,
        })?;
    }
    let previous_time_s = plan
        .resume
        .as_ref()
        .map_or(0.0, |r| r.checkpoint.header.render_time_s);
    let run = run_passes(
        integrator,
        options,
        control,
        PassLoop {
            first_pass,
            resumed_passes,
            shard: plan.shard,
            fingerprint: &fingerprint,
            previous_time_s,
            checkpoint: plan.checkpoint.take(),
            watch: plan.watch.as_deref_mut(),
        },
        start,
    )?;
    let sums = integrator.sums()?;
    if let Some(watch) = plan.watch {
        watch.finish(&sums)?;
    }
    let extra_images = integrator.extra_images()?;
    let integrator_stats = stats_since(integrator.stats(), &stats_before);
    let settings = integrator.settings();
    let seconds = start.elapsed().as_secs_f64();
    let film = film_with_aovs(&sums, aovs)?;
    let stats = render_stats(gpu, scene, options, &sums, &run, integrator_stats, seconds);
    let record = PartRecord {
        fingerprint,
        passes: PassRanges::single(first_pass..first_pass + sums.passes),
        samples_per_pass: sums.samples_per_pass,
        second_moments: sums.sum_sq.is_some(),
        shard: (!plan.shard.is_whole()).then_some(plan.shard),
    };
    let total_render_time_s = previous_time_s + seconds;
    let metadata = render_metadata(&stats, settings, &record, total_render_time_s);
    Ok(RenderOutput {
        film,
        sums,
        record,
        first_pass,
        total_render_time_s,
        metadata,
        stats,
        extra_images,
    })
}

/// What decides the image of a render of `scene` with `options` on `integrator`.
fn fingerprint_of(
    scene: &Scene,
    options: &RenderOptions,
    integrator: &dyn Integrator,
) -> Fingerprint {
    Fingerprint::new(
        scene,
        options.width,
        options.height,
        options.seed,
        options.integrator.name(),
        integrator.samples_per_pass(),
        integrator.settings(),
    )
}

/// The film of `sums` (with its standard error where the sums have one) and the AOVs.
fn film_with_aovs(sums: &FilmSums, aovs: aov::Aovs) -> Result<Film, RenderError> {
    let mut film = sums.to_film()?;
    if let Some(stderr) = sums.stderr() {
        film.set_stderr(stderr)?;
    }
    film.set_depth(aovs.depth)?;
    film.set_triangle_id(aovs.triangle_id)?;
    film.set_normal(aovs.normal)?;
    Ok(film)
}

/// The figures of a render that took `seconds` and ended with `sums`; takes the GPU's
/// profile.
fn render_stats(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
    sums: &FilmSums,
    run: &PassRun,
    integrator_stats: IntegratorStats,
    seconds: f64,
) -> RenderStats {
    let (_, peak_gpu_bytes) = gpu.memory_bytes();
    let profile = gpu.take_profile();
    let pixels = options.width as f64 * options.height as f64;
    RenderStats {
        scene: scene.name.clone(),
        triangles: scene.triangles.len(),
        width: options.width,
        height: options.height,
        spp: sums.spp(),
        passes: sums.passes,
        seed: options.seed,
        integrator: options.integrator.name().into(),
        tracer: options.tracer.name().into(),
        device: device_description(gpu),
        render_time_s: seconds,
        samples_per_second: run.passes_rendered as f64 * sums.samples_per_pass as f64 * pixels
            / seconds.max(1e-9),
        rays_traced: integrator_stats.rays_traced,
        rays_per_second: integrator_stats.rays_traced as f64 / seconds.max(1e-9),
        peak_gpu_bytes,
        stopped_early: run.stopped,
        relative_mse: run.reference_error.map(|e| e.relative_mse),
        relative_mse_excess: run.reference_error.and_then(|e| e.excess),
        counters: integrator_stats.counters,
        kernels: profile.summary(),
        profile: profile.tree(),
    }
}

/// The image files' header: the render's figures, the integrator's `settings` and the
/// part `record`, with the render time of every run of the film.
fn render_metadata(
    stats: &RenderStats,
    settings: Vec<(String, String)>,
    record: &PartRecord,
    render_time_s: f64,
) -> RenderMetadata {
    let mut extra = vec![
        ("scene".to_string(), stats.scene.clone()),
        ("rays_traced".to_string(), stats.rays_traced.to_string()),
        ("passes".to_string(), stats.passes.to_string()),
    ];
    if stats.stopped_early {
        extra.push(("stopped_early".into(), "true".into()));
    }
    extra.extend(settings);
    extra.extend(record.extra());
    RenderMetadata {
        spp: stats.spp.min(u32::MAX as u64) as u32,
        seed: stats.seed,
        integrator: stats.integrator.clone(),
        tracer: stats.tracer.clone(),
        device: stats.device.clone(),
        render_time_s,
        extra,
    }
}

/// What an integrator counted since `before`.
fn stats_since(mut now: IntegratorStats, before: &IntegratorStats) -> IntegratorStats {
    now.rays_traced -= before.rays_traced.min(now.rays_traced);
    for (key, value) in &mut now.counters {
        *value -= before.counters.get(key).copied().unwrap_or(0).min(*value);
    }
    now
}

/// The integrator `options` asks for, on its own tracer, ready to render passes (for
/// callers that drive passes themselves: tests, previews, resumed renders).
pub fn create_integrator(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
) -> Result<Box<dyn Integrator>, RenderError> {
    device_fit::check(gpu, scene, options)?;
    let triangles = scene.gpu_triangles();
    let tracer = options.tracer.create(gpu, &triangles)?;
    integrator_on(gpu, scene, options, &triangles, tracer)
}

/// Says so when `options.spp` is not a whole number of the integrator's passes: a render
/// runs whole passes, so it rounds up (a `cbpt` pass adds 4 samples per pixel).
/// `u32::MAX` bounds nothing (a render for a time), so it is not rounded.
pub(crate) fn warn_if_spp_rounds_up(options: &RenderOptions, integrator: &dyn Integrator) {
    let per_pass = integrator.samples_per_pass().max(1);
    if options.spp != u32::MAX && options.spp % per_pass != 0 {
        log::warn!(
            "{} renders {per_pass} samples per pixel a pass: {} spp asked, {} rendered",
            integrator.name(),
            options.spp,
            options.spp.div_ceil(per_pass) * per_pass
        );
    }
}

/// Builds the integrator `options` asks for; it takes the tracer over.
fn integrator_on(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
    triangles: &[GpuTriangle],
    tracer: Box<dyn Tracer>,
) -> Result<Box<dyn Integrator>, RenderError> {
    let camera = scene.camera.frame(options.width, options.height);
    Ok(match options.integrator {
        IntegratorKind::Pt => Box::new(integrator::pt::PtIntegrator::new(
            gpu,
            tracer,
            &integrator::pt::PtScene::new(scene),
            &camera,
            &pt_options(gpu, options),
        )?),
        IntegratorKind::Bpt | IntegratorKind::Light => {
            // The CPU integrators cast their own rays; the tracer is not needed.
            drop(tracer);
            let mode = match options.integrator {
                IntegratorKind::Light => integrator::bpt::BidirMode::Light,
                _ => integrator::bpt::BidirMode::Bpt,
            };
            Box::new(integrator::bpt::BptIntegrator::new(
                mode,
                scene,
                &camera,
                &integrator::bpt::BptOptions {
                    seed: options.seed,
                    max_depth: options.max_depth,
                    rr_depth: options.rr_depth,
                    technique_images: options.bdpt_techniques,
                    ..Default::default()
                },
            ))
        }
        IntegratorKind::LvcBdpt | IntegratorKind::CisLbdpt => {
            Box::new(integrator::lvc::LvcIntegrator::new(
                gpu,
                tracer,
                &integrator::pt::PtScene::new(scene),
                &camera,
                &lvc_options(gpu, options),
            )?)
        }
        IntegratorKind::Cbpt => Box::new(integrator::cbpt::CbptIntegrator::new(
            scene,
            &camera,
            &integrator::cbpt::CbptOptions {
                seed: options.seed,
                max_depth: options.max_depth,
                rr_depth: options.rr_depth,
                settings: options.cbpt,
                pipelined: true,
            },
            Some((gpu, tracer)),
        )?),
        kind => eye_integrator(gpu, scene, options, kind, triangles, camera, tracer)?,
    })
}

/// `pt`'s settings: the render's, its material sorting where it pays on `gpu` unless
/// chosen.
fn pt_options(gpu: &Gpu, options: &RenderOptions) -> integrator::pt::PtOptions {
    integrator::pt::PtOptions {
        spp: options.spp,
        time_limit: options.time_limit,
        seed: options.seed,
        max_depth: options.max_depth,
        rr_depth: options.rr_depth,
        sort: options
            .sort_materials
            .unwrap_or_else(|| integrator::pt::sort_pays(gpu)),
        strategy: options.strategy,
        ..Default::default()
    }
}

/// `lvc-bdpt`'s and `cis-lbdpt`'s settings: the variant's, with the render's seed, depths,
/// spp and technique images.
fn lvc_options(gpu: &Gpu, options: &RenderOptions) -> integrator::lvc::LvcOptions {
    let variant = options
        .integrator
        .lvc_variant()
        .unwrap_or(integrator::lvc::Variant::LvcBdpt);
    let mut lvc = options
        .lvc
        .options(variant, integrator::lvc::sort_pays(gpu));
    lvc.seed = options.seed;
    lvc.max_depth = options.max_depth;
    lvc.rr_depth = options.rr_depth;
    lvc.spp = options.spp;
    lvc.technique_images = options.bdpt_techniques;
    lvc
}

/// The PDACRT workloads' integrators (`kind`: `primary`, `ao`, `shadow`, `reflection`,
/// `path`), on the scene's diffuse and emissive colours.
fn eye_integrator(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
    kind: IntegratorKind,
    triangles: &[GpuTriangle],
    camera: CameraFrame,
    tracer: Box<dyn Tracer>,
) -> Result<Box<dyn Integrator>, RenderError> {
    let triangle_material: Vec<u32> = scene.triangles.iter().map(|t| t.material).collect();
    let materials: Vec<GpuMaterial> = scene
        .materials
        .iter()
        .map(|m| GpuMaterial {
            diffuse: m.diffuse.extend(0.0).into(),
            emission: m.emission.extend(0.0).into(),
        })
        .collect();
    Ok(Box::new(EyeIntegrator::new(
        gpu,
        tracer,
        &EyeInputs {
            triangles,
            triangle_material: &triangle_material,
            materials: &materials,
            camera,
            bounds: scene.bounds(),
            light: shadow_light(scene),
        },
        &EyeOptions {
            integrator: kind,
            spp: options.spp,
            seed: options.seed,
            ao_rays: options.ao_rays,
            ..Default::default()
        },
    )?))
}

/// What the pass loop continues from and hands its film to.
struct PassLoop<'f, 'h, 'w> {
    /// Global index of the film's first pass.
    first_pass: u32,
    /// Passes the film holds before the loop starts (from a checkpoint).
    resumed_passes: u32,
    shard: Shard,
    fingerprint: &'f Fingerprint,
    /// Render time of the runs before this one.
    previous_time_s: f64,
    checkpoint: Option<CheckpointHook<'h>>,
    watch: Option<&'w mut (dyn FilmWatch + 'h)>,
}

/// How the pass loop ended.
struct PassRun {
    stopped: bool,
    /// Passes this run added.
    passes_rendered: u32,
    reference_error: Option<film::ReferenceError>,
}

/// Seconds between two relative-MSE readings while a render runs (each reads the film).
const MSE_INTERVAL_S: f64 = 0.5;

/// Seconds a batch of passes should last, where an integrator could take more passes
/// per call: between batches the loop asks whether to stop, checks the time limit and
/// saves checkpoints, so this bounds how late each of those comes. Each batch also pays
/// a fixed cost (for `pt` on small films on lavapipe about 0.1 s per call: the host round
/// trips of its bounces and of PDACRT), so short batches cost throughput (0.25 s batches
/// made small `pt` renders 1.4–1.5× slower there); 2 s keeps it to a few percent once
/// the batches have grown. A fast device still gets its integrator's full batches: the
/// size follows the measured time per pass.
const BATCH_TARGET_S: f64 = 2.0;

/// Passes for the next batch: what lasts about [`BATCH_TARGET_S`] (or the time left) at
/// `seconds_per_pass`, within 1 ..= `most`.
fn batch_size(seconds_per_pass: f64, time_left_s: Option<f64>, most: u32) -> u32 {
    let budget = time_left_s.map_or(BATCH_TARGET_S, |t| t.min(BATCH_TARGET_S));
    let fits = (budget / seconds_per_pass.max(1e-9)).floor();
    (fits.min(most as f64) as u32).clamp(1, most.max(1))
}

/// The render loop every integrator shares: batches of passes until the shard's passes
/// are done, the time ran out (checked after each batch) or the caller asks to stop
/// (checked before each batch); the film is handed to the checkpoint hook when due.
/// Batches last about [`BATCH_TARGET_S`]; how passes are grouped never changes the film.
fn run_passes(
    integrator: &mut dyn Integrator,
    options: &RenderOptions,
    control: RenderControl<'_>,
    mut job: PassLoop<'_, '_, '_>,
    start: Instant,
) -> Result<PassRun, RenderError> {
    let watched_batch_s = job.watch.as_ref().and_then(|w| w.batch_target_s());
    let per_pass = integrator.samples_per_pass().max(1);
    let block = job.shard.passes(options.spp.div_ceil(per_pass));
    let target_spp = (block.end - block.start) as u64 * per_pass as u64;
    let mut passes = job.resumed_passes;
    let mut next = job.first_pass.saturating_add(passes);
    let mut stopped = false;
    let mut reference_error = None;
    let mut mse_read_at = f64::NEG_INFINITY;
    let mut saved_at = 0.0;
    // The first batch is one pass: it measures the time per pass (and pays for the
    // shaders' first compilation).
    let mut batch = 1;
    while next < block.end {
        if (control.stop)() {
            stopped = true;
            break;
        }
        let count = batch.min(block.end - next);
        // Once the film holds a pass, the time limit gives up a pass in progress too,
        // where the integrator can (`cbpt`'s passes, 4 spp of the whole film in steps,
        // last minutes on a large film): the render then ends within a step of its
        // limit. The first pass always finishes: an image needs one.
        let film_has_a_pass = passes > 0;
        let abandon = || {
            (control.abandon)()
                || (film_has_a_pass && past(options.time_limit, start.elapsed().as_secs_f64()))
        };
        let done;
        (done, batch) = render_batch(integrator, (next, count), &abandon, || {
            batch_time_left_s(options.time_limit, start, watched_batch_s)
        })?;
        next += done;
        passes += done;
        let elapsed_s = start.elapsed().as_secs_f64();
        let out_of_time = past(options.time_limit, elapsed_s);
        if done < count {
            // A pass given up: the film holds the passes before it.
            if !out_of_time {
                stopped = true;
                break;
            }
            log::info!("the time limit gave up pass {next} in progress");
        } else if out_of_time && !film_has_a_pass {
            log::warn!(
                "the first pass took {elapsed_s:.1} s, past the time limit of {:.1} s: an \
                 image needs one pass",
                options.time_limit.unwrap_or_default()
            );
        }
        let last = next == block.end || out_of_time;
        if let Some(reference) = &options.reference {
            if last || elapsed_s - mse_read_at >= MSE_INTERVAL_S {
                reference_error = error_against(reference, integrator)?;
                mse_read_at = elapsed_s;
            }
        }
        let progress = Progress {
            passes,
            spp: passes as u64 * per_pass as u64,
            target_spp,
            elapsed_s,
            time_limit: options.time_limit,
            relative_mse: reference_error.map(|e| e.relative_mse),
        };
        (control.progress)(&progress);
        if let Some(watch) = job.watch.as_deref_mut() {
            watch.batch(&progress, &mut || integrator.sums())?;
        }
        if !last {
            saved_at = job.save_checkpoint_if_due(integrator, elapsed_s, saved_at)?;
        }
        if out_of_time {
            break;
        }
    }
    if let (true, Some(reference)) = (stopped, &options.reference) {
        reference_error = error_against(reference, integrator)?;
    }
    Ok(PassRun {
        stopped,
        passes_rendered: passes - job.resumed_passes,
        reference_error,
    })
}

/// Renders passes `first..first + count`, unless `abandon` gives one up; returns the
/// passes done and the size of the next batch, from the time per pass just measured and
/// the seconds `time_left_s` leaves it.
fn render_batch(
    integrator: &mut dyn Integrator,
    (first, count): (u32, u32),
    abandon: &dyn Fn() -> bool,
    time_left_s: impl FnOnce() -> Option<f64>,
) -> Result<(u32, u32), RenderError> {
    let batch_start = Instant::now();
    let done = integrator.render_passes_or_abandon(first, count, abandon)?;
    let time_left_s = time_left_s();
    let next = batch_size(
        batch_start.elapsed().as_secs_f64() / count as f64,
        time_left_s,
        integrator.passes_per_call(),
    );
    Ok((done, next))
}

/// Whether a render `elapsed_s` seconds in has reached its time limit.
fn past(time_limit: Option<f64>, elapsed_s: f64) -> bool {
    time_limit.is_some_and(|t| elapsed_s >= t)
}

/// The most seconds the next batch may last: what the time limit leaves of the render
/// begun at `start`, and no more than a watcher's batch target.
fn batch_time_left_s(
    time_limit: Option<f64>,
    start: Instant,
    watched_batch_s: Option<f64>,
) -> Option<f64> {
    let time_left_s = time_limit.map(|t| t - start.elapsed().as_secs_f64());
    match (time_left_s, watched_batch_s) {
        (Some(t), Some(w)) => Some(t.min(w)),
        (t, w) => t.or(w),
    }
}

/// The film's error against `reference` now.
fn error_against(
    reference: &film::Reference,
    integrator: &mut dyn Integrator,
) -> Result<Option<film::ReferenceError>, RenderError> {
    Ok(reference.error(&integrator.sums()?.mean()))
}

impl PassLoop<'_, '_, '_> {
    /// Hands the film to the checkpoint hook, if there is one and its interval has passed
    /// since the film was last handed to it at `saved_at`; returns when it last was (a
    /// save that failed is tried again an interval later, as one that succeeded).
    fn save_checkpoint_if_due(
        &mut self,
        integrator: &mut dyn Integrator,
        elapsed_s: f64,
        saved_at: f64,
    ) -> Result<f64, RenderError> {
        if let Some(hook) = &mut self.checkpoint {
            if elapsed_s - saved_at >= hook.every_s {
                let sums = integrator.sums()?;
                let saved = (hook.save)(&FilmSnapshot {
                    sums: &sums,
                    fingerprint: self.fingerprint,
                    shard: self.shard,
                    first_pass: self.first_pass,
                    render_time_s: self.previous_time_s + elapsed_s,
                });
                // A checkpoint that cannot be saved (a full disk, say) is a warning, not
                // the end of the render: the film is still being made, the disk may have
                // room by the next one, and the caller saves the finished film anyway.
                if let Err(e) = saved {
                    log::warn!(
                        "{e}; the render goes on and saves its checkpoint again in {} s",
                        hook.every_s
                    );
                }
                return Ok(elapsed_s);
            }
        }
        Ok(saved_at)
    }
}

/// The `shadow` integrator's light: the scene's first point light (RGB intensity
/// averaged into one white intensity), else one inside the top of the scene box, bright
/// enough that the irradiance at the box centre is about 1.
pub fn shadow_light(scene: &Scene) -> glam::Vec4 {
    match scene.point_lights.first() {
        Some(l) => l.position.extend(l.intensity.element_sum() / 3.0),
        None => {
            let position = crate::bench::workloads::shadow_light(scene);
            let d = (position - scene.bounds().center()).length();
            position.extend(d * d)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::IntegratorStats;
    use std::time::Duration;

    /// A one-pixel integrator whose pass 0 is one step and every later pass
    /// `later_steps`, each step a sleep of 1 ms, asking `abandon` after each step as
    /// `cbpt` does.
    struct SleptSteps {
        later_steps: u32,
        sums: FilmSums,
        given_up: Option<u32>,
    }

    impl SleptSteps {
        fn new(later_steps: u32) -> Self {
            Self {
                later_steps,
                sums: FilmSums::new(1, 1, 1, false),
                given_up: None,
            }
        }
    }

    impl Integrator for SleptSteps {
        fn name(&self) -> &'static str {
            "slept-steps"
        }

        fn render_passes(&mut self, first: u32, count: u32) -> Result<(), IntegratorError> {
            self.render_passes_or_abandon(first, count, &|| false)
                .map(|_| ())
        }

        fn render_passes_or_abandon(
            &mut self,
            first: u32,
            count: u32,
            abandon: &dyn Fn() -> bool,
        ) -> Result<u32, IntegratorError> {
            for (done, pass) in (first..first + count).enumerate() {
                let steps = if pass == 0 { 1 } else { self.later_steps };
                for _ in 0..steps {
                    std::thread::sleep(Duration::from_millis(1));
                    if abandon() {
                        self.given_up = Some(pass);
                        return Ok(done as u32);
                    }
                }
                self.sums.add_pass(&[[1.0; 3]]);
            }
            Ok(count)
        }

        fn sums(&mut self) -> Result<FilmSums, IntegratorError> {
            Ok(self.sums.clone())
        }

        fn restore(&mut self, sums: &FilmSums) -> Result<(), IntegratorError> {
            self.sums = sums.clone();
            Ok(())
        }

        fn stats(&self) -> IntegratorStats {
            IntegratorStats::default()
        }
    }

    /// Runs the pass loop over `integrator` for up to 1000 passes with `time_limit`.
    fn run_for(integrator: &mut SleptSteps, time_limit: f64) -> PassRun {
        let scene = crate::scene::builtin("cornell-box").unwrap();
        let mut options = RenderOptions::resolve(
            &scene,
            Some(1),
            Some(1),
            Some(1000),
            Some(0),
            Some(IntegratorKind::Primary),
            None,
        )
        .unwrap();
        options.time_limit = Some(time_limit);
        let fingerprint = Fingerprint {
            scene_digest: String::new(),
            settings: Vec::new(),
        };
        let job = PassLoop {
            first_pass: 0,
            resumed_passes: 0,
            shard: Shard::WHOLE,
            fingerprint: &fingerprint,
            previous_time_s: 0.0,
            checkpoint: None,
            watch: None,
        };
        let control = RenderControl {
            progress: &mut |_| {},
            stop: &|| false,
            abandon: &|| false,
        };
        run_passes(integrator, &options, control, job, Instant::now()).unwrap()
    }

    /// The time limit gives up a long pass in progress once the film holds one, and the
    /// render ends as one that ran out of time, not as one stopped early.
    #[test]
    fn the_time_limit_gives_up_a_long_pass_once_the_film_holds_one() {
        // Pass 1 would last 100 s; the limit comes 0.5 s into it at most.
        let mut long = SleptSteps::new(100_000);
        let run = run_for(&mut long, 0.5);
        assert_eq!(long.given_up, Some(1));
        assert_eq!((run.passes_rendered, long.sums.passes), (1, 1));
        assert!(!run.stopped);
    }

    /// The first pass always finishes, however short the time limit: an image needs one.
    #[test]
    fn the_first_pass_finishes_past_the_time_limit() {
        let mut one = SleptSteps::new(3);
        let run = run_for(&mut one, 0.0);
        assert_eq!(one.given_up, None);
        assert_eq!((run.passes_rendered, one.sums.passes), (1, 1));
        assert!(!run.stopped);
    }

    #[test]
    fn batches_last_about_the_target_within_the_integrators_bounds() {
        assert_eq!(batch_size(0.0625, None, 682), 32);
        assert_eq!(batch_size(4.0, None, 682), 1);
        assert_eq!(batch_size(1e-7, None, 682), 682);
        assert_eq!(batch_size(0.0625, Some(0.125), 682), 2);
        assert_eq!(batch_size(0.0625, Some(-1.0), 682), 1);
        assert_eq!(batch_size(0.0625, None, 0), 1);
    }
}
