//! `splitray bench pt SCENE`: the path tracer with and without material sorting, in
//! one run. Both renders use the same seed, so they must give the same film bit for
//! bit (checked: a difference is an error, not a figure).

use std::fmt;
use std::time::Instant;

use serde::Serialize;

use crate::integrator::pt::{render_pt, PtOptions, PtScene};
use crate::render::device_description;
use crate::scene::Scene;
use crate::trace::TracerKind;
use crate::vk::{self, Gpu};

#[derive(Clone, Debug)]
pub struct PtBenchOptions {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: i32,
    pub tracer: TracerKind,
    pub seed: u64,
}

impl Default for PtBenchOptions {
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            spp: 16,
            max_depth: -1,
            tracer: TracerKind::Pdacrt,
            seed: 0,
        }
    }
}

/// One timed render.
#[derive(Clone, Debug, Serialize)]
pub struct PtRun {
    pub sort: bool,
    pub seconds: f64,
    pub samples_per_second: f64,
    pub rays: u64,
    pub mrays_per_second: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct PtBenchReport {
    pub date: String,
    pub device: String,
    pub scene: String,
    pub triangles: usize,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: i32,
    pub tracer: String,
    pub runs: Vec<PtRun>,
    /// Whether both films agree bit for bit (always true, or the bench fails).
    pub identical: bool,
}

impl fmt::Display for PtBenchReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "bench pt {} ({} triangles) {}x{} {} spp max_depth {} tracer {} on {} ({})",
            self.scene,
            self.triangles,
            self.width,
            self.height,
            self.spp,
            self.max_depth,
            self.tracer,
            self.device,
            self.date
        )?;
        writeln!(
            f,
            "{:<10} {:>10} {:>14} {:>12} {:>10}",
            "sorting", "seconds", "samples/s", "rays", "Mrays/s"
        )?;
        for r in &self.runs {
            writeln!(
                f,
                "{:<10} {:>10.3} {:>14.0} {:>12} {:>10.3}",
                if r.sort { "on" } else { "off" },
                r.seconds,
                r.samples_per_second,
                r.rays,
                r.mrays_per_second
            )?;
        }
        writeln!(
            f,
            "films identical with and without sorting: {}",
            self.identical
        )
    }
}

/// Renders `scene` with sorting on, then off (after an untimed warm-up of one pass).
pub fn run(gpu: &Gpu, scene: &Scene, options: &PtBenchOptions) -> vk::Result<PtBenchReport> {
    let pt = PtScene::new(scene);
    let camera = scene.camera.frame(options.width, options.height);
    let mut tracer = options.tracer.create(gpu, &pt.triangles)?;
    let base = PtOptions {
        spp: options.spp.max(1),
        seed: options.seed,
        max_depth: options.max_depth,
        ..Default::default()
    };
    render_pt(
        gpu,
        tracer.as_mut(),
        &pt,
        &camera,
        &PtOptions { spp: 1, ..base },
        &mut |_| {},
    )?;
    let mut runs = Vec::new();
    let mut films = Vec::new();
    for sort in [true, false] {
        let start = Instant::now();
        let out = render_pt(
            gpu,
            tracer.as_mut(),
            &pt,
            &camera,
            &PtOptions { sort, ..base },
            &mut |_| {},
        )?;
        let seconds = start.elapsed().as_secs_f64().max(1e-9);
        let samples = options.width as f64 * options.height as f64 * out.passes as f64;
        runs.push(PtRun {
            sort,
            seconds,
            samples_per_second: samples / seconds,
            rays: out.rays_traced,
            mrays_per_second: out.rays_traced as f64 / seconds * 1e-6,
        });
        films.push(out.sum_rgb);
    }
    let identical = films[0]
        .iter()
        .flatten()
        .zip(films[1].iter().flatten())
        .all(|(a, b)| a.to_bits() == b.to_bits());
    if !identical {
        return Err(vk::VkError::Usage(
            "bench pt: sorting changed the film (a bug)".into(),
        ));
    }
    Ok(PtBenchReport {
        date: super::today(),
        device: device_description(gpu),
        scene: scene.name.clone(),
        triangles: scene.triangles.len(),
        width: options.width,
        height: options.height,
        spp: options.spp,
        max_depth: options.max_depth,
        tracer: options.tracer.name().into(),
        runs,
        identical,
    })
}
