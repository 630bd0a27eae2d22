//! `bpt` and `light`: bidirectional path tracing and light tracing on the CPU (all cores,
//! rayon), the reference every bidirectional method of splitray is checked against and
//! CBPT's "standard BPT" baseline (CBPT §6.2: the same path-sampling code on the CPU).
//!
//! A pass gives every pixel one camera subpath and one light subpath (`bpt`; only the
//! light subpaths for `light`) and evaluates all of Veach's techniques (s, t) with the
//! machinery of [`crate::bidir`]: s = 0 (camera subpaths that hit an emitter), s = 1
//! (next-event estimation with a fresh light sample), s, t ≥ 2 (connections) and t = 1
//! (light tracing: every light vertex connected to the pinhole and splatted to the pixel
//! it projects to), weighted by the balance heuristic. A pixel's pass estimate is its
//! camera-side contributions plus the splats that landed on it divided by the pass's
//! light subpaths (one per pixel) — the same per-pass [`FilmSums`] as `pt`, so standard
//! errors, `--reference`, checkpoints and merging work alike.
//!
//! Conventions (scene, depth, roulette, shading normals) are `pt`'s so that the images
//! agree; [`crate::bidir`] documents each where it is implemented.

pub mod pass;
pub mod technique_images;

use crate::bidir::{Connector, Counters, CpuScene, PinholeCamera, TechniqueCounts, WalkSettings};
use crate::film::FilmSums;
use crate::integrator::{
    check_film_size, Integrator, IntegratorError, IntegratorStats, NamedImage, SceneFrame,
};
use crate::scene::{CameraFrame, Scene};

use self::pass::{pass_estimate, render_chunks, PassInputs};
use self::technique_images::TechniqueImages;

/// Which integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BidirMode {
    /// Bidirectional path tracing: every technique.
    Bpt,
    /// Light tracing alone (t = 1, emitters seen directly included).
    Light,
}

/// Settings of the bidirectional integrators.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BptOptions {
    pub seed: u64,
    /// Mitsuba's max_depth (< 0: unbounded).
    pub max_depth: i32,
    /// Russian roulette from this vertex on.
    pub rr_depth: u32,
    /// Keep one image per technique ([`Integrator::extra_images`]).
    pub technique_images: bool,
    /// The technique counts of the balance heuristic; `None`: the mode's own
    /// ([`TechniqueCounts::bpt`], [`TechniqueCounts::light_tracer`]). A count of 0 turns
    /// a technique family off (the tests render single families this way).
    pub counts: Option<TechniqueCounts>,
    /// Pixels per unit of parallel work.
    pub chunk_pixels: u32,
}

impl Default for BptOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            max_depth: -1,
            rr_depth: 5,
            technique_images: false,
            counts: None,
            chunk_pixels: 256,
        }
    }
}

/// The CPU bidirectional integrator (`bpt` or `light`).
pub struct BptIntegrator {
    mode: BidirMode,
    scene: CpuScene,
    camera: PinholeCamera,
    options: BptOptions,
    settings: WalkSettings,
    sums: FilmSums,
    techniques: Option<TechniqueImages>,
    counters: Counters,
}

impl BptIntegrator {
    pub fn new(mode: BidirMode, scene: &Scene, camera: &CameraFrame, options: &BptOptions) -> Self {
        Self::with_scene(mode, CpuScene::new(scene), camera, options)
    }

    /// On a scene already prepared for the CPU.
    pub fn with_scene(
        mode: BidirMode,
        scene: CpuScene,
        camera: &CameraFrame,
        options: &BptOptions,
    ) -> Self {
        let camera = PinholeCamera::new(camera);
        let light_paths = camera.pixel_count() as f32;
        let counts = options.counts.unwrap_or(match mode {
            BidirMode::Bpt => TechniqueCounts::bpt(light_paths),
            BidirMode::Light => TechniqueCounts::light_tracer(light_paths),
        });
        let (w, h) = (camera.width(), camera.height());
        Self {
            mode,
            scene,
            camera,
            options: *options,
            settings: WalkSettings {
                max_depth: options.max_depth,
                rr_depth: options.rr_depth,
                counts,
            },
            sums: FilmSums::new(w, h, 1, true),
            techniques: options.technique_images.then(|| TechniqueImages::new(w, h)),
            counters: Counters::default(),
        }
    }

    /// What was counted so far.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Light subpaths per pass: one per pixel.
    fn light_paths_per_pass(&self) -> f64 {
        self.camera.pixel_count() as f64
    }

    fn render_pass(&mut self, pass: u32) {
        let _span = tracing::info_span!("bidir pass", pass).entered();
        let inputs = PassInputs {
            connector: Connector {
                scene: &self.scene,
                camera: &self.camera,
                settings: &self.settings,
            },
            camera: &self.camera,
            seed: self.options.seed,
            camera_paths: self.mode == BidirMode::Bpt,
            keep_techniques: self.techniques.is_some(),
            chunk_pixels: self.options.chunk_pixels as usize,
        };
        let chunks = render_chunks(&inputs, pass);
        let light_paths = self.light_paths_per_pass();
        let estimate = pass_estimate(&chunks, self.camera.pixel_count(), light_paths);
        self.sums.add_pass(&estimate);
        if let Some(t) = &mut self.techniques {
            t.add_pass(&chunks, light_paths);
        }
        for chunk in &chunks {
            self.counters += chunk.counters;
        }
    }
}

impl Integrator for BptIntegrator {
    fn name(&self) -> &'static str {
        match self.mode {
            BidirMode::Bpt => "bpt",
            BidirMode::Light => "light",
        }
    }

    fn render_passes(&mut self, first: u32, count: u32) -> Result<(), IntegratorError> {
        for pass in first..first + count {
            self.render_pass(pass);
        }
        Ok(())
    }

    fn sums(&mut self) -> Result<FilmSums, IntegratorError> {
        Ok(self.sums.clone())
    }

    fn restore(&mut self, sums: &FilmSums) -> Result<(), IntegratorError> {
        check_film_size(sums, self.camera.width(), self.camera.height(), 1)?;
        self.sums = sums.clone();
        self.sums.keep_second_moments();
        if let Some(t) = &mut self.techniques {
            *t = TechniqueImages::new(self.camera.width(), self.camera.height());
        }
        Ok(())
    }

    fn stats(&self) -> IntegratorStats {
        let c = &self.counters;
        let counters = [
            ("camera_paths", c.camera_paths),
            ("light_paths", c.light_paths),
            ("vertices", c.vertices),
            ("connections", c.connections),
            ("basic_contributions", c.basic_contributions),
            ("non_finite_dropped", c.non_finite),
        ];
        IntegratorStats::with_counters(c.rays, &counters)
    }

    fn settings(&self) -> Vec<(String, String)> {
        let c = &self.settings.counts;
        vec![
            ("max_depth".into(), self.options.max_depth.to_string()),
            ("rr_depth".into(), self.options.rr_depth.to_string()),
            (
                "light_paths_per_pass".into(),
                self.light_paths_per_pass().to_string(),
            ),
            (
                "technique_counts".into(),
                format!(
                    "hit {} nee {} connect {} trace {} trace_emitter {}",
                    c.emitter_hit,
                    c.light_sample,
                    c.connection,
                    c.light_trace,
                    c.light_trace_emitter
                ),
            ),
        ]
    }

    /// The CPU scene (its BVH built again, as the CPU BVH must be) and the camera; the
    /// scene's lights move with their triangles.
    fn set_frame(&mut self, frame: &SceneFrame<'_>) -> Result<(), IntegratorError> {
        if (frame.camera.width, frame.camera.height) != (self.camera.width(), self.camera.height())
        {
            return Err(IntegratorError::Usage(
                "a frame cannot change the film size".to_string(),
            ));
        }
        if frame.geometry_changed() {
            self.scene = CpuScene::new(frame.scene);
        }
        self.camera = PinholeCamera::new(&frame.camera);
        Ok(())
    }

    fn extra_images(&mut self) -> Result<Vec<NamedImage>, IntegratorError> {
        Ok(self
            .techniques
            .as_ref()
            .map(|t| t.images())
            .unwrap_or_default())
    }
}
