//! `cbpt`: combinatorial bidirectional path tracing (Pajot, Barthe, Paulin and Poulin,
//! "Combinatorial Bidirectional Path-Tracing for Efficient Hybrid CPU/GPU Rendering",
//! CGF 30(2), 2011).
//!
//! Each step samples a population couple — N_C camera paths and N_L light paths — on
//! every core with `bpt`'s random walks ([`population`]), combines every camera path with
//! every light path ([`combine`], §3.1) from the combination data of every linking
//! segment (visibility and the shading tuples of both ends, [`layout`]), and light-traces
//! N_T more light paths into a separate light-tracing image ([`light_tracing`]). The
//! balance heuristic counts the N_L light paths each camera path meets
//! ([`crate::bidir::combinatorial`]). Camera paths start at the shuffled stratified image
//! positions of §3.2 ([`steps`]); a pass uses them all once: 4 samples per pixel.
//! The steps run with two population couples in flight ([`pipeline`], Algorithm 2).
//!
//! The combination data come from the GPU ([`gpu`]: three kernels in double-buffered
//! batches, visibility through any [`Tracer`]) or from their CPU twins on every core
//! ([`cpu_kernels::evaluate`]; `--cbpt-combine cpu`).
//!
//! Conventions (scene, depth, roulette, shading normals, the pinhole) are `bpt`'s; the
//! same seed gives the same image whatever the thread count.

pub mod calibrate;
pub mod combine;
pub mod compare;
pub mod cpu_kernels;
pub mod gpu;
pub mod layout;
pub mod light_tracing;
pub mod options;
pub mod pipeline;
pub mod population;
pub mod steps;

use std::sync::Arc;
use std::time::Instant;

pub use self::gpu::GpuCombiner;
pub use self::options::{CameraPaths, CbptOptions, CbptSettings, Combination};

use self::calibrate::Equation4;
use self::combine::Linking;
use self::layout::{CombinationData, Kinds, Tables};
use self::pipeline::{run_steps, CpuSide, Evaluator, StepTimes};
use self::population::SamplingInputs;
use self::steps::{PassPlan, StepId, Streams, SAMPLES_PER_PIXEL};
use super::bpt::{BidirMode, BptIntegrator, BptOptions};
use super::{check_film_size, Integrator, IntegratorError, IntegratorStats, SceneFrame};
use crate::bidir::combinatorial::CombinatorialCounts;
use crate::bidir::{Connector, Counters, CpuScene, PinholeCamera, WalkSettings};
use crate::film::FilmSums;
use crate::scene::{CameraFrame, Scene};
use crate::trace::Tracer;
use crate::vk::Gpu;

/// The combination on every core: [`cpu_kernels::evaluate`].
pub struct CpuEvaluator<'a> {
    pub scene: &'a CpuScene,
}

impl Evaluator for CpuEvaluator<'_> {
    type Uploaded = Arc<Tables>;
    type Pending = CombinationData;

    fn upload(&mut self, tables: Arc<Tables>) -> Result<Arc<Tables>, IntegratorError> {
        Ok(tables)
    }

    fn launch(&mut self, tables: Arc<Tables>) -> Result<CombinationData, IntegratorError> {
        Ok(cpu_kernels::evaluate(self.scene, &tables, Kinds::ALL))
    }

    fn finish(&mut self, data: CombinationData) -> Result<CombinationData, IntegratorError> {
        Ok(data)
    }
}

/// Where the combination runs.
pub enum Backend {
    Cpu,
    Gpu(Box<GpuCombiner>),
}

impl Backend {
    /// The backend `settings` ask for; the GPU one takes `device`'s tracer over.
    pub fn new(
        settings: &CbptSettings,
        scene: &CpuScene,
        device: Option<(&Gpu, Box<dyn Tracer>)>,
    ) -> Result<Self, IntegratorError> {
        Ok(match (settings.combination, device) {
            (Combination::Cpu, _) => Self::Cpu,
            (Combination::Gpu, Some((gpu, tracer))) => Self::Gpu(Box::new(GpuCombiner::new(
                gpu,
                tracer,
                scene,
                settings.batch,
            )?)),
            (Combination::Gpu, None) => {
                return Err(IntegratorError::Usage(
                    "cbpt: the GPU combination needs a device (or --cbpt-combine cpu)".into(),
                ))
            }
        })
    }

    /// Runs `steps` on this backend, until `abandon` says to stop ([`run_steps`]).
    pub fn run(
        &mut self,
        setup: &Setup,
        steps: Vec<StepId>,
        pipelined: bool,
        abandon: &dyn Fn() -> bool,
    ) -> Result<pipeline::StepsOutput, IntegratorError> {
        let cpu = setup.cpu_side();
        match self {
            Self::Cpu => {
                let mut evaluator = CpuEvaluator {
                    scene: &setup.scene,
                };
                run_steps(&cpu, &mut evaluator, steps, pipelined, abandon)
            }
            Self::Gpu(g) => run_steps(&cpu, g.as_mut(), steps, pipelined, abandon),
        }
    }
}

/// What the steps of every pass share: the scene, the camera, the population sizes and
/// the MIS counts they imply.
pub struct Setup {
    pub scene: CpuScene,
    pub camera: PinholeCamera,
    /// N_C in use.
    pub camera_paths: u32,
    /// N_L in use.
    pub light_paths: u32,
    /// N_T.
    pub light_traced: u32,
    pub plan: PassPlan,
    pub streams: Streams,
    pub counts: CombinatorialCounts,
    /// Walks and weights with [`CombinatorialCounts::walk`].
    pub walk: WalkSettings,
    /// Weights of two-segment paths ([`CombinatorialCounts::of_path`]).
    pub direct: WalkSettings,
}

impl Setup {
    /// The setup for N_C = `camera_paths` and N_L = `light_paths`.
    pub fn new(
        scene: CpuScene,
        camera: &CameraFrame,
        options: &CbptOptions,
        camera_paths: u32,
        light_paths: u32,
    ) -> Result<Self, IntegratorError> {
        let camera = PinholeCamera::new(camera);
        let pixels = camera.pixel_count() as u32;
        let plan = PassPlan::new(pixels, camera_paths);
        let light_traced = options.settings.light_traced;
        let most = plan.steps as u64 * light_paths.max(light_traced) as u64;
        if most > u32::MAX as u64 {
            return Err(IntegratorError::Usage(format!(
                "cbpt: {} steps per pass of {light_paths} light paths and {light_traced} \
                 light-traced paths need more than 2^32 random streams; raise --cbpt-nc",
                plan.steps
            )));
        }
        let counts = CombinatorialCounts {
            light_paths: light_paths as f32,
            light_traced: (plan.steps as u64 * light_traced as u64) as f32
                / SAMPLES_PER_PIXEL as f32,
        };
        let walk = WalkSettings {
            max_depth: options.max_depth,
            rr_depth: options.rr_depth,
            counts: counts.walk(),
        };
        Ok(Self {
            scene,
            camera,
            camera_paths,
            light_paths,
            light_traced,
            plan,
            streams: Streams::new(options.seed),
            counts,
            walk,
            direct: WalkSettings {
                counts: counts.of_path(2),
                ..walk
            },
        })
    }

    /// The CPU side of the step loop.
    pub fn cpu_side(&self) -> CpuSide<'_> {
        let connector = |settings| Connector {
            scene: &self.scene,
            camera: &self.camera,
            settings,
        };
        CpuSide {
            sampling: SamplingInputs {
                scene: &self.scene,
                camera: &self.camera,
                settings: &self.walk,
                streams: self.streams,
                light_paths: self.light_paths,
            },
            linking: Linking {
                connector: connector(&self.walk),
                direct: connector(&self.direct),
                counts: self.counts,
            },
            plan: self.plan,
            pixels: self.camera.pixel_count() as u32,
            light_traced: self.light_traced,
        }
    }

    /// The steps of passes `passes`.
    pub fn steps(&self, passes: std::ops::Range<u32>) -> Vec<StepId> {
        let plan = self.plan;
        passes
            .flat_map(|pass| {
                (0..plan.steps).map(move |step| StepId {
                    pass,
                    step,
                    cameras: plan.step_cameras(step),
                })
            })
            .collect()
    }
}

/// The CBPT integrator.
pub struct CbptIntegrator {
    setup: Setup,
    backend: Backend,
    options: CbptOptions,
    equation4: Option<Equation4>,
    sums: FilmSums,
    counters: Counters,
    times: StepTimes,
}

impl CbptIntegrator {
    /// CBPT on `scene` through `camera`; `device` (a GPU and the tracer of its
    /// visibility tests) serves the GPU combination and is not needed for the CPU one.
    pub fn new(
        scene: &Scene,
        camera: &CameraFrame,
        options: &CbptOptions,
        device: Option<(&Gpu, Box<dyn Tracer>)>,
    ) -> Result<Self, IntegratorError> {
        options
            .settings
            .check()
            .map_err(|e| IntegratorError::Usage(format!("cbpt: {e}")))?;
        let cpu = CpuScene::new(scene);
        let mut backend = Backend::new(&options.settings, &cpu, device)?;
        let light_paths = options.settings.light_paths;
        let (setup, equation4) = match options.settings.camera_paths {
            CameraPaths::Fixed(n) => (Setup::new(cpu, camera, options, n, light_paths)?, None),
            CameraPaths::Equation4 => {
                let e = equation_4(scene, camera, options, &mut backend)?;
                log::info!("cbpt: {e}");
                let setup = Setup::new(cpu, camera, options, e.camera_paths, e.light_paths)?;
                (setup, Some(e))
            }
        };
        let (w, h) = (setup.camera.width(), setup.camera.height());
        Ok(Self {
            setup,
            backend,
            options: *options,
            equation4,
            sums: FilmSums::new(w, h, SAMPLES_PER_PIXEL, true),
            counters: Counters::default(),
            times: StepTimes::default(),
        })
    }

    /// The backend, to run steps outside passes (benchmarks).
    pub fn backend_mut(&mut self) -> (&Setup, &mut Backend) {
        (&self.setup, &mut self.backend)
    }

    pub fn setup(&self) -> &Setup {
        &self.setup
    }

    /// What was counted so far.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Where the steps' time went so far.
    pub fn step_times(&self) -> StepTimes {
        self.times
    }

    /// Equation 4's measurement, when N_C came from it.
    pub fn equation4(&self) -> Option<Equation4> {
        self.equation4
    }
}

/// Measures t_b (a pass of `bpt` on a film of at most 64 × 64 of the same view) and
/// t_s (pipelined steps of the default N_C × N_L pairs, after one to warm up) and
/// solves Equation 4.
fn equation_4(
    scene: &Scene,
    camera: &CameraFrame,
    options: &CbptOptions,
    backend: &mut Backend,
) -> Result<Equation4, IntegratorError> {
    let _span = tracing::info_span!("cbpt equation 4").entered();
    let small = CameraFrame {
        width: camera.width.min(64),
        height: camera.height.min(64),
        ..*camera
    };
    let bpt_options = BptOptions {
        seed: options.seed,
        max_depth: options.max_depth,
        rr_depth: options.rr_depth,
        ..Default::default()
    };
    let mut bpt = BptIntegrator::new(BidirMode::Bpt, scene, &small, &bpt_options);
    bpt.render_passes(0, 1)?;
    let t = Instant::now();
    bpt.render_passes(1, 1)?;
    let pair_seconds = t.elapsed().as_secs_f64() / (small.width * small.height) as f64;
    let light_paths = options.settings.light_paths;
    let camera_paths = options::DEFAULT_CAMERA_PATHS;
    let setup = Setup::new(
        CpuScene::new(scene),
        camera,
        options,
        camera_paths,
        light_paths,
    )?;
    // Four passes hold four steps at least: one to warm up, three timed (where a pass is
    // one step, a small film's, the steps of later passes).
    let steps = setup.steps(0..4);
    let timed = &steps[1..steps.len().min(4)];
    backend.run(&setup, steps[..1].to_vec(), false, &|| false)?;
    let t = Instant::now();
    backend.run(&setup, timed.to_vec(), true, &|| false)?;
    let step_seconds = t.elapsed().as_secs_f64() / timed.len() as f64;
    // A small film's steps hold fewer camera paths than N_C: the pairs a step holds.
    let cameras = timed.iter().map(|s| s.cameras.len() as u64).sum::<u64>() / timed.len() as u64;
    let pairs = cameras * light_paths as u64;
    Ok(Equation4::solve(pair_seconds, step_seconds, pairs))
}

impl Integrator for CbptIntegrator {
    fn name(&self) -> &'static str {
        "cbpt"
    }

    fn samples_per_pass(&self) -> u32 {
        SAMPLES_PER_PIXEL
    }

    /// Passes of one call run as one pipeline (it drains at the end of a call).
    fn passes_per_call(&self) -> u32 {
        64
    }

    fn render_passes(&mut self, first: u32, count: u32) -> Result<(), IntegratorError> {
        self.render_passes_or_abandon(first, count, &|| false)
            .map(|_| ())
    }

    /// A pass is 4 spp of the whole film, in steps of N_C camera paths: on a large film
    /// it lasts long, so a stop request gives up the pass between two steps.
    fn render_passes_or_abandon(
        &mut self,
        first: u32,
        count: u32,
        abandon: &dyn Fn() -> bool,
    ) -> Result<u32, IntegratorError> {
        let _span = tracing::info_span!("cbpt passes", first, count).entered();
        let steps = self.setup.steps(first..first + count);
        let out = self
            .backend
            .run(&self.setup, steps, self.options.pipelined, abandon)?;
        for (_, estimate) in &out.passes {
            self.sums.add_pass(estimate);
        }
        self.counters += out.counters;
        self.times += out.times;
        Ok(out.passes.len() as u32)
    }

    fn sums(&mut self) -> Result<FilmSums, IntegratorError> {
        Ok(self.sums.clone())
    }

    fn restore(&mut self, sums: &FilmSums) -> Result<(), IntegratorError> {
        let camera = &self.setup.camera;
        check_film_size(sums, camera.width(), camera.height(), SAMPLES_PER_PIXEL)?;
        self.sums = sums.clone();
        self.sums.keep_second_moments();
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
            ("steps", self.times.steps),
        ];
        IntegratorStats::with_counters(c.rays, &counters)
    }

    /// The CPU scene (its BVH built again, as `bpt`'s, and with it the emitter table,
    /// whose areas and probabilities move with their triangles), the camera, and on the
    /// GPU the tracer's geometry and the ray offset. The population sizes, the pass plan
    /// and the MIS counts depend on the film and the settings only; N_C and N_L from
    /// Equation 4 stay those measured on the first frame (a measurement of time, which
    /// no two renders repeat exactly).
    ///
    /// The pipeline keeps two population couples in flight only within a call to
    /// [`Integrator::render_passes`]: `run_steps` finishes the last step's combination
    /// and joins its CPU thread before it returns, and frames change between calls. So
    /// no step straddles a frame change — every population of the next call is sampled
    /// on the posed scene and combined against its geometry — without draining anything
    /// here; the GPU side waits for the device all the same before it moves the tracer.
    fn set_frame(&mut self, frame: &SceneFrame<'_>) -> Result<(), IntegratorError> {
        let camera = &self.setup.camera;
        if (frame.camera.width, frame.camera.height) != (camera.width(), camera.height()) {
            return Err(IntegratorError::Usage(
                "a frame cannot change the film size".to_string(),
            ));
        }
        if frame.geometry_changed() {
            self.setup.scene = CpuScene::new(frame.scene);
        }
        if let Backend::Gpu(g) = &mut self.backend {
            g.move_to_frame(frame, &self.setup.scene)?;
        }
        self.setup.camera = PinholeCamera::new(&frame.camera);
        Ok(())
    }

    fn settings(&self) -> Vec<(String, String)> {
        let s = &self.setup;
        vec![
            ("max_depth".into(), self.options.max_depth.to_string()),
            ("rr_depth".into(), self.options.rr_depth.to_string()),
            ("cbpt_camera_paths".into(), s.camera_paths.to_string()),
            ("cbpt_light_paths".into(), s.light_paths.to_string()),
            ("cbpt_light_traced".into(), s.light_traced.to_string()),
            ("cbpt_steps_per_pass".into(), s.plan.steps.to_string()),
            (
                "cbpt_combination".into(),
                self.options.settings.combination.to_string(),
            ),
        ]
    }
}
