//! The step loop of Algorithm 2 with two population couples in flight (Fig. 4).
//!
//! Two threads: the *combination driver* (the calling thread, which owns the GPU
//! combination and its tracer, as the paper's "CUDA-specific thread" does) and the *CPU
//! thread*, whose sampling, combining and light tracing run on every core (rayon). Per
//! step t the CPU thread
//!
//! 1. samples the population couple {x}_t, {y}_t and packs its linking vertices;
//! 2. hands them to the driver, which uploads them (`upload_async`), waits for the
//!    combination of step t − 1 (`sync_gpu_comp`) and hands it back, then launches step
//!    t's (`gpu_comp_async`);
//! 3. samples and traces step t's N_T light-tracing paths (`sample({y_lt})`,
//!    `compute_lt()`) while the device computes;
//! 4. combines step t − 1 (`combine()`).
//!
//! So the CPU combines step t − 1 and samples step t + 1 while the device combines step
//! t — the device's time hides behind the CPU's, or the CPU's behind the device's,
//! whichever is shorter. The order of step 2 is the paper's: step t is launched only
//! after step t − 1's data went back, so a device whose submissions execute in the
//! submitting thread (lavapipe) does not hold step t − 1's data back behind step t's
//! work (tests/suite/cbpt_pipeline.rs holds the loop to that). Not pipelined, every step
//! waits for its own combination (the synchronous reference of `bench cbpt`). The
//! image is the same either way: each step's work depends on that step alone, and
//! passes are summed in order.

use std::collections::BTreeMap;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;

use super::combine::{combine, Linking, StepData};
use super::layout::{CombinationData, Tables};
use super::light_tracing::{light_trace, Splat};
use super::population::{Population, SamplingInputs};
use super::steps::{ImagePositions, PassPlan, StepId, SAMPLES_PER_PIXEL};
use crate::bidir::Counters;
use crate::integrator::IntegratorError;

/// Computes the combination data of population couples, at most two at a time, in
/// Algorithm 2's three calls: `upload_async` ([`Evaluator::upload`]), `gpu_comp_async`
/// ([`Evaluator::launch`]) and `sync_gpu_comp` ([`Evaluator::finish`]), in step order.
pub trait Evaluator {
    type Uploaded;
    type Pending;
    fn upload(&mut self, tables: Arc<Tables>) -> Result<Self::Uploaded, IntegratorError>;
    fn launch(&mut self, uploaded: Self::Uploaded) -> Result<Self::Pending, IntegratorError>;
    fn finish(&mut self, pending: Self::Pending) -> Result<CombinationData, IntegratorError>;

    /// Upload and launch at once.
    fn start(&mut self, tables: Arc<Tables>) -> Result<Self::Pending, IntegratorError> {
        let uploaded = self.upload(tables)?;
        self.launch(uploaded)
    }
}

/// Where the time of the steps went (sums over the steps).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepTimes {
    pub steps: u64,
    /// CPU thread: sampling the population couples.
    pub sample: Duration,
    /// CPU thread: packing the linking vertices.
    pub pack: Duration,
    /// CPU thread: sampling and tracing the N_T light paths.
    pub light_tracing: Duration,
    /// CPU thread: waiting for a step's combination data.
    pub wait: Duration,
    /// CPU thread: combine() and splatting.
    pub combine: Duration,
    /// Driver: uploading a step and submitting its batches (on a device whose
    /// submissions run to completion, lavapipe, their execution too).
    pub start: Duration,
    /// Driver: waiting for a step's last download and copying its data out.
    pub finish: Duration,
    /// Wall time of the step loops.
    pub wall: Duration,
}

impl std::ops::AddAssign for StepTimes {
    fn add_assign(&mut self, o: Self) {
        self.steps += o.steps;
        self.sample += o.sample;
        self.pack += o.pack;
        self.light_tracing += o.light_tracing;
        self.wait += o.wait;
        self.combine += o.combine;
        self.start += o.start;
        self.finish += o.finish;
        self.wall += o.wall;
    }
}

/// The CPU side of the steps: sampling, combining, light tracing.
pub struct CpuSide<'a> {
    pub sampling: SamplingInputs<'a>,
    pub linking: Linking<'a>,
    pub plan: PassPlan,
    pub pixels: u32,
    /// N_T.
    pub light_traced: u32,
}

/// What the steps of some passes produced.
#[derive(Default)]
pub struct StepsOutput {
    /// Each pass's estimate, in pass order.
    pub passes: Vec<(u32, Vec<[f64; 3]>)>,
    pub counters: Counters,
    pub times: StepTimes,
}

/// Runs `steps` in order, the combination on `evaluator`; the estimates of the passes
/// whose every step ran come back. `abandon` is asked after each step is launched: on
/// `true` no further step starts (the steps under way finish, and a pass they leave
/// unfinished is dropped).
pub fn run_steps<E: Evaluator>(
    cpu: &CpuSide,
    evaluator: &mut E,
    steps: Vec<StepId>,
    pipelined: bool,
    abandon: &dyn Fn() -> bool,
) -> Result<StepsOutput, IntegratorError> {
    // Named apart so that a timeline's pipelined stretches can be told from the
    // synchronous ones (tools/timeline_overlap.py --within).
    let _span = if pipelined {
        tracing::info_span!("cbpt steps pipelined", steps = steps.len())
    } else {
        tracing::info_span!("cbpt steps synchronous", steps = steps.len())
    }
    .entered();
    let start = Instant::now();
    let (tables_tx, tables_rx) = sync_channel::<Arc<Tables>>(1);
    let (data_tx, data_rx) = sync_channel::<CombinationData>(1);
    let (driven, cpu_out) = std::thread::scope(|scope| {
        let cpu_thread = std::thread::Builder::new()
            .name("cbpt cpu".into())
            .spawn_scoped(scope, || {
                cpu_loop(cpu, steps, tables_tx, data_rx, pipelined)
            })
            .expect("spawn the CBPT CPU thread");
        let driven = drive(evaluator, tables_rx, data_tx, pipelined, abandon);
        let cpu_out = cpu_thread
            .join()
            .unwrap_or_else(|p| std::panic::resume_unwind(p));
        (driven, cpu_out)
    });
    let driver_times = driven?;
    let mut out = cpu_out;
    out.times += driver_times;
    out.times.wall += start.elapsed();
    Ok(out)
}

/// The combination driver. Pipelined, it follows Algorithm 2: it uploads step t as it
/// arrives, then waits for step t − 1's combination and hands it back, then launches
/// step t — so the CPU combines step t − 1 while the device computes step t, and on a
/// device whose submissions run to completion (lavapipe) step t − 1's data is not held
/// back by step t's work. Otherwise each step is uploaded, launched and finished in turn.
fn drive<E: Evaluator>(
    evaluator: &mut E,
    tables_rx: Receiver<Arc<Tables>>,
    data_tx: SyncSender<CombinationData>,
    pipelined: bool,
    abandon: &dyn Fn() -> bool,
) -> Result<StepTimes, IntegratorError> {
    let mut times = StepTimes::default();
    let finish = |e: &mut E, p: E::Pending, times: &mut StepTimes| {
        let t = Instant::now();
        let data = e.finish(p);
        times.finish += t.elapsed();
        data
    };
    let mut pending: Option<E::Pending> = None;
    while let Ok(tables) = tables_rx.recv() {
        let t = Instant::now();
        let uploaded = evaluator.upload(tables)?;
        times.start += t.elapsed();
        if let Some(p) = pending.take() {
            if data_tx.send(finish(evaluator, p, &mut times)?).is_err() {
                return Ok(times);
            }
        }
        let t = Instant::now();
        let launched = evaluator.launch(uploaded)?;
        times.start += t.elapsed();
        if pipelined {
            pending = Some(launched);
        } else if data_tx
            .send(finish(evaluator, launched, &mut times)?)
            .is_err()
        {
            return Ok(times);
        }
        if abandon() {
            break;
        }
    }
    // Given up or done: the CPU thread's next step has nowhere to go, so it stops.
    drop(tables_rx);
    if let Some(p) = pending {
        // The CPU thread may have stopped; the data then has nobody to go to.
        let _ = data_tx.send(finish(evaluator, p, &mut times)?);
    }
    Ok(times)
}

/// A step whose combination is under way.
struct Sampled {
    population: Population,
    tables: Arc<Tables>,
}

/// The CPU thread (see the module docs).
fn cpu_loop(
    cpu: &CpuSide,
    steps: Vec<StepId>,
    tables_tx: SyncSender<Arc<Tables>>,
    data_rx: Receiver<CombinationData>,
    pipelined: bool,
) -> StepsOutput {
    let mut out = StepsOutput::default();
    let mut images = PassImages::new(cpu);
    let mut positions: Option<(u32, ImagePositions)> = None;
    let mut pending: Option<Sampled> = None;
    let receive = |out: &mut StepsOutput| {
        let t = Instant::now();
        let data = data_rx.recv().ok();
        out.times.wait += t.elapsed();
        data
    };
    for id in steps {
        if positions.as_ref().is_none_or(|(p, _)| *p != id.pass) {
            let seed = cpu.sampling.streams.shuffle;
            positions = Some((id.pass, ImagePositions::new(cpu.pixels, id.pass, seed)));
        }
        let (_, pos) = positions.as_ref().expect("made above");
        let (pass, step) = (id.pass, id.step);
        let t = Instant::now();
        let population = Population::sample(&cpu.sampling, id, pos, &mut out.counters);
        out.times.sample += t.elapsed();
        let t = Instant::now();
        let tables = Arc::new(Tables::new(&population));
        out.times.pack += t.elapsed();
        out.counters.connections += tables.segments();
        out.counters.rays += tables.segments();
        if tables_tx.send(tables.clone()).is_err() {
            return out;
        }
        let t = Instant::now();
        let splats = light_trace(
            &cpu.sampling,
            &cpu.linking,
            pass,
            step,
            cpu.light_traced,
            &mut out.counters,
        );
        images.add_splats(pass, &splats);
        out.times.light_tracing += t.elapsed();
        out.times.steps += 1;
        let sampled = Sampled { population, tables };
        let ready = if pipelined {
            pending.replace(sampled)
        } else {
            Some(sampled)
        };
        if let Some(s) = ready {
            let Some(data) = receive(&mut out) else {
                return out;
            };
            combine_step(cpu, &s, &data, &mut images, &mut out);
        }
    }
    drop(tables_tx);
    if let Some(s) = pending {
        if let Some(data) = receive(&mut out) {
            combine_step(cpu, &s, &data, &mut images, &mut out);
        }
    }
    out
}

fn combine_step(
    cpu: &CpuSide,
    s: &Sampled,
    data: &CombinationData,
    images: &mut PassImages,
    out: &mut StepsOutput,
) {
    let t = Instant::now();
    let step = StepData {
        population: &s.population,
        tables: &s.tables,
        data,
    };
    let values = combine(&cpu.linking, step, &mut out.counters);
    let pass = s.population.id.pass;
    if let Some(estimate) = images.add_camera_values(pass, &s.population.pixels, &values) {
        out.passes.push((pass, estimate));
    }
    out.times.combine += t.elapsed();
}

/// The bidirectional and light-tracing images of the passes in flight.
struct PassImages {
    pixels: usize,
    steps: u32,
    /// Light-traced paths per pass (0: no light tracing).
    light_traced: u64,
    open: BTreeMap<u32, PassImage>,
}

struct PassImage {
    bidirectional: Vec<[f64; 3]>,
    light_tracing: Vec<[f64; 3]>,
    combined_steps: u32,
}

impl PassImages {
    fn new(cpu: &CpuSide) -> Self {
        Self {
            pixels: cpu.pixels as usize,
            steps: cpu.plan.steps,
            light_traced: cpu.plan.steps as u64 * cpu.light_traced as u64,
            open: BTreeMap::new(),
        }
    }

    fn image(&mut self, pass: u32) -> &mut PassImage {
        let pixels = self.pixels;
        self.open.entry(pass).or_insert_with(|| PassImage {
            bidirectional: vec![[0.0; 3]; pixels],
            light_tracing: vec![[0.0; 3]; pixels],
            combined_steps: 0,
        })
    }

    fn add_splats(&mut self, pass: u32, splats: &[Splat]) {
        let image = self.image(pass);
        for (pixel, v) in splats {
            add(&mut image.light_tracing[*pixel as usize], *v);
        }
    }

    /// Splats a step's camera-path values (f^b); returns the pass's estimate when this
    /// was its last step.
    fn add_camera_values(
        &mut self,
        pass: u32,
        pixels: &[u32],
        values: &[Vec3],
    ) -> Option<Vec<[f64; 3]>> {
        let steps = self.steps;
        let image = self.image(pass);
        for (pixel, v) in pixels.iter().zip(values) {
            add(&mut image.bidirectional[*pixel as usize], *v);
        }
        image.combined_steps += 1;
        if image.combined_steps < steps {
            return None;
        }
        let image = self.open.remove(&pass).expect("open above");
        let light_scale = if self.light_traced > 0 {
            1.0 / self.light_traced as f64
        } else {
            0.0
        };
        let camera_scale = 1.0 / SAMPLES_PER_PIXEL as f64;
        Some(
            image
                .bidirectional
                .iter()
                .zip(&image.light_tracing)
                .map(|(b, l)| std::array::from_fn(|c| b[c] * camera_scale + l[c] * light_scale))
                .collect(),
        )
    }
}

fn add(pixel: &mut [f64; 3], v: Vec3) {
    for (p, x) in pixel.iter_mut().zip(v.to_array()) {
        *p += x as f64;
    }
}
