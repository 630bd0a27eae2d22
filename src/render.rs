//! A render from start to finish: scene → GPU data → tracer → integrator passes → film,
//! with the statistics a user profiles by.

use std::time::Instant;

use serde::Serialize;

use crate::film::{Film, FilmError, RenderMetadata};
use crate::integrator::{self, GpuMaterial, IntegratorKind, PassInputs, PassOptions};
use crate::scene::{Scene, SceneError};
use crate::trace::{GpuTriangle, TracerKind};
use crate::vk::{self, Gpu, KernelTime};

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Scene(#[from] Box<SceneError>),
    #[error(transparent)]
    Gpu(#[from] vk::VkError),
    #[error(transparent)]
    Film(#[from] FilmError),
    #[error("{0}")]
    Options(String),
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
    /// `pt`: Mitsuba's max_depth (1 = emitters seen directly, 2 = direct light; < 0
    /// unbounded). From the scene's `[render] max_depth`, else unbounded.
    pub max_depth: i32,
    /// `pt`: Russian roulette from this depth on (Mitsuba's default 5).
    pub rr_depth: u32,
    /// `pt`: sort paths by material key before shading.
    pub sort_materials: bool,
    /// `pt`: which estimators contribute light.
    pub strategy: integrator::pt::Strategy,
    /// Stop after the pass during which this many seconds ran out (`spp` is then the
    /// most passes).
    pub time_limit: Option<f64>,
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
            sort_materials: true,
            strategy: Default::default(),
            time_limit: None,
        };
        if options.width == 0
            || options.height == 0
            || options.width > 16384
            || options.height > 16384
        {
            return Err(RenderError::Options(format!(
                "film size {}x{} is outside 1..=16384",
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
    pub spp: u32,
    pub seed: u64,
    pub integrator: String,
    pub tracer: String,
    pub device: String,
    pub render_time_s: f64,
    pub rays_traced: u64,
    pub rays_per_second: f64,
    pub peak_gpu_bytes: u64,
    /// GPU time per kernel (timestamp queries), longest first.
    pub kernels: Vec<KernelTime>,
}

pub struct RenderOutput {
    pub film: Film,
    pub metadata: RenderMetadata,
    pub stats: RenderStats,
}

/// A one-line description of the device for logs and file headers.
pub fn device_description(gpu: &Gpu) -> String {
    let info = gpu.info();
    format!("{} ({} {})", info.name, info.driver_name, info.driver_info)
}

/// Renders `scene`. `progress` is told the passes done so far.
pub fn render(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
    progress: &mut dyn FnMut(u32),
) -> Result<RenderOutput, RenderError> {
    let limit = gpu.info().limits.max_storage_buffer_range;
    scene.check_fits(limit, size_of::<GpuTriangle>() as u64)?;
    let triangles: Vec<GpuTriangle> = scene
        .triangles
        .iter()
        .map(|t| GpuTriangle::new(t.p))
        .collect();
    let triangle_material: Vec<u32> = scene.triangles.iter().map(|t| t.material).collect();
    let materials: Vec<GpuMaterial> = scene
        .materials
        .iter()
        .map(|m| GpuMaterial {
            diffuse: m.diffuse.extend(0.0).into(),
            emission: m.emission.extend(0.0).into(),
        })
        .collect();
    let camera = scene.camera.frame(options.width, options.height);

    gpu.wait_idle()?;
    let _ = gpu.take_profile();
    gpu.reset_peak_memory();
    let start = Instant::now();
    let mut tracer = options.tracer.create(gpu, &triangles)?;
    if options.integrator == IntegratorKind::Pt {
        return render_pt(gpu, scene, options, tracer.as_mut(), start, progress);
    }
    let output = integrator::render_passes(
        gpu,
        tracer.as_mut(),
        &PassInputs {
            triangles: &triangles,
            triangle_material: &triangle_material,
            materials: &materials,
            camera,
            scene_radius: scene.bounds().radius(),
            light: shadow_light(scene),
        },
        &PassOptions {
            integrator: options.integrator,
            spp: options.spp,
            seed: options.seed,
            ao_rays: options.ao_rays,
            ..Default::default()
        },
        progress,
    )?;
    drop(tracer);
    let seconds = start.elapsed().as_secs_f64();
    let (_, peak_gpu_bytes) = gpu.memory_bytes();

    let mean: Vec<[f32; 3]> = output
        .sum_rgb
        .iter()
        .map(|s| {
            let w = s[3].max(1.0);
            [s[0] / w, s[1] / w, s[2] / w]
        })
        .collect();
    let mut film = Film::from_mean_rgb(options.width, options.height, &mean)?;
    film.set_depth(output.depth)?;
    film.set_triangle_id(output.triangle_id)?;
    film.set_normal(output.normal.iter().map(|n| [n[0], n[1], n[2]]).collect())?;

    Ok(finish(
        gpu,
        scene,
        options,
        film,
        options.spp,
        seconds,
        peak_gpu_bytes,
        output.rays_traced,
        vec![],
    ))
}

/// Statistics and header metadata of a finished render.
#[allow(clippy::too_many_arguments)]
fn finish(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
    film: Film,
    spp: u32,
    seconds: f64,
    peak_gpu_bytes: u64,
    rays_traced: u64,
    extra: Vec<(String, String)>,
) -> RenderOutput {
    let device = device_description(gpu);
    let stats = RenderStats {
        scene: scene.name.clone(),
        triangles: scene.triangles.len(),
        width: options.width,
        height: options.height,
        spp,
        seed: options.seed,
        integrator: options.integrator.name().into(),
        tracer: options.tracer.name().into(),
        device: device.clone(),
        render_time_s: seconds,
        rays_traced,
        rays_per_second: rays_traced as f64 / seconds.max(1e-9),
        peak_gpu_bytes,
        kernels: gpu.take_profile().summary(),
    };
    let mut all_extra = vec![
        ("scene".to_string(), scene.name.clone()),
        ("rays_traced".to_string(), rays_traced.to_string()),
    ];
    all_extra.extend(extra);
    let metadata = RenderMetadata {
        spp,
        seed: options.seed,
        integrator: options.integrator.name().into(),
        tracer: options.tracer.name().into(),
        device,
        render_time_s: seconds,
        extra: all_extra,
    };
    RenderOutput {
        film,
        metadata,
        stats,
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

/// The `pt` integrator's half of [`render`].
fn render_pt(
    gpu: &Gpu,
    scene: &Scene,
    options: &RenderOptions,
    tracer: &mut dyn crate::trace::Tracer,
    start: Instant,
    progress: &mut dyn FnMut(u32),
) -> Result<RenderOutput, RenderError> {
    let pt_scene = integrator::pt::PtScene::new(scene);
    let camera = scene.camera.frame(options.width, options.height);
    let output = integrator::pt::render_pt(
        gpu,
        tracer,
        &pt_scene,
        &camera,
        &integrator::pt::PtOptions {
            spp: options.spp,
            time_limit: options.time_limit,
            seed: options.seed,
            max_depth: options.max_depth,
            rr_depth: options.rr_depth,
            sort: options.sort_materials,
            strategy: options.strategy,
            ..Default::default()
        },
        progress,
    )?;
    let seconds = start.elapsed().as_secs_f64();
    let (_, peak_gpu_bytes) = gpu.memory_bytes();
    let (mean, _) = output.mean_and_stderr();
    let film = Film::from_mean_rgb(options.width, options.height, &mean)?;
    Ok(finish(
        gpu,
        scene,
        options,
        film,
        output.passes,
        seconds,
        peak_gpu_bytes,
        output.rays_traced,
        vec![
            ("max_depth".into(), options.max_depth.to_string()),
            ("rr_depth".into(), options.rr_depth.to_string()),
            ("sort_materials".into(), options.sort_materials.to_string()),
        ],
    ))
}
