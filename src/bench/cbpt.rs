//! `splitray bench cbpt SCENE`: the measurements of the CBPT paper (§6) in one run.
//!
//! 1. **Combination throughput** (Table 1): visibility tests, camera and light shading
//!    tuples per second of one population couple of the paper's sizes (N_C = 2000,
//!    N_L = 15), on the GPU (upload, batches and downloads included) through each tracer
//!    asked for, against their CPU twins on every core, in alternating runs. The GPU's
//!    data are first checked against the CPU's (visibility bit for bit).
//! 2. **Batch size** (Fig. 6): the GPU throughput of visibility and camera shading for
//!    batch sizes from 2^10 to 2^20 segments.
//! 3. **Basic contributions per second** (Table 3, §6.2): f_{i,j} values per second,
//!    sampling and splatting included, of CBPT with N_T = 0 and N_T = 1500 (GPU
//!    combination), of CBPT with the combination on the CPU, and of `bpt` on the CPU with
//!    the same code, in alternating blocks; medians.
//! 4. **A step's parts** (Algorithm 2): the time of sampling, packing, light tracing,
//!    combining, submitting and waiting per step, the GPU's busy time per step (its
//!    timestamps: kernels, and the uploads and downloads on the transfer stream), and
//!    the wall time per step pipelined (two couples in flight) and synchronous, in
//!    alternating blocks: how much of the shorter of the CPU's work and the
//!    combination's hides behind the longer (the paper's GPU behind its CPU; on lavapipe,
//!    whose "GPU" is the same cores, the CPU behind the combination).
//! 5. **Equal time** (with `--reference`): `pt`, `bpt` and `cbpt` for the same time
//!    ([`super::bdpt`]), their relative MSE and its ratios; since CBPT's pass is coarse,
//!    the ratios are also given for MSE × seconds (inverse efficiency).

use std::fmt;
use std::sync::Arc;
use std::time::{Duration, Instant};

use serde::Serialize;

use super::bdpt::{self as bdpt_bench, BdptBenchOptions, BdptBenchReport};
use super::{median, EvenMedian};
use crate::bidir::{Counters, CpuScene};
use crate::film::Reference;
use crate::integrator::bpt::{BidirMode, BptIntegrator, BptOptions};
use crate::integrator::cbpt::compare;
use crate::integrator::cbpt::cpu_kernels::evaluate;
use crate::integrator::cbpt::layout::{CombinationData, Kinds, Tables};
use crate::integrator::cbpt::pipeline::{Evaluator, StepTimes};
use crate::integrator::cbpt::population::Population;
use crate::integrator::cbpt::steps::ImagePositions;
use crate::integrator::cbpt::{
    Backend, CbptIntegrator, CbptOptions, CbptSettings, Combination, GpuCombiner, Setup,
};
use crate::integrator::{Integrator, IntegratorKind};
use crate::render::{device_description, RenderError};
use crate::scene::Scene;
use crate::trace::TracerKind;
use crate::vk::{Gpu, ProfileLog};

#[derive(Clone, Debug)]
pub struct CbptBenchOptions {
    pub width: u32,
    pub height: u32,
    /// Tracers of the visibility throughput; the first serves everything else.
    pub tracers: Vec<TracerKind>,
    /// Steps per measured block (throughput and step timings).
    pub steps: u32,
    /// Alternating blocks (or runs) per comparison.
    pub rounds: u32,
    /// Batch sizes of the batch-size sweep.
    pub batches: Vec<u32>,
    /// Seconds per integrator of the equal-time comparison.
    pub seconds: f64,
    pub max_depth: i32,
    pub seed: u64,
    /// A reference of this film size.
    pub reference: Option<Arc<Reference>>,
}

impl Default for CbptBenchOptions {
    fn default() -> Self {
        Self {
            width: 160,
            height: 120,
            tracers: vec![TracerKind::Pdacrt, TracerKind::CpuBvh],
            steps: 6,
            rounds: 3,
            batches: vec![1 << 10, 1 << 12, 1 << 14, 1 << 16, 1 << 18, 1 << 20],
            seconds: 30.0,
            max_depth: -1,
            seed: 0,
            reference: None,
        }
    }
}

/// Table 1: one kind of combination data.
#[derive(Clone, Debug, Serialize)]
pub struct ThroughputRow {
    pub kind: String,
    /// The tracer, for visibility on the GPU.
    pub tracer: Option<String>,
    pub segments: u64,
    /// Millions per second, medians.
    pub gpu: f64,
    pub cpu: f64,
}

/// Fig. 6: one batch size.
#[derive(Clone, Debug, Serialize)]
pub struct BatchRow {
    pub batch: u32,
    /// Millions of visibility tests and of camera shading tuples per second.
    pub visibility: f64,
    pub shading: f64,
}

/// Table 3: one contestant.
#[derive(Clone, Debug, Serialize)]
pub struct ContributionRow {
    pub name: String,
    /// Median basic contributions per second.
    pub per_second: f64,
    pub seconds: f64,
}

/// Algorithm 2: a step's parts, in milliseconds per step.
#[derive(Clone, Debug, Default, Serialize)]
pub struct StepRow {
    pub mode: String,
    pub steps: u64,
    pub sample: f64,
    pub pack: f64,
    pub light_tracing: f64,
    pub combine: f64,
    pub cpu_waiting: f64,
    pub submit: f64,
    pub finish: f64,
    /// GPU busy time (the union of its timestamp scopes), kernels and transfers.
    pub gpu: f64,
    /// Of which uploads and downloads.
    pub gpu_transfers: f64,
    pub wall: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct CbptBenchReport {
    pub date: String,
    pub device: String,
    pub cpu: String,
    pub threads: usize,
    pub scene: String,
    pub triangles: usize,
    pub width: u32,
    pub height: u32,
    pub tracer: String,
    pub population: String,
    /// GPU data equal to the CPU's (`integrator::cbpt::compare`): visibility bits that
    /// differ, shading tuples that do not agree, and tuples along an endpoint's tangent
    /// plane that agree on f alone (not mismatches).
    pub visibility_mismatches: u64,
    pub shading_mismatches: u64,
    pub shading_tangent: u64,
    pub throughput: Vec<ThroughputRow>,
    pub batches: Vec<BatchRow>,
    pub contributions: Vec<ContributionRow>,
    pub steps: Vec<StepRow>,
    pub equal_time: Option<BdptBenchReport>,
}

fn ms(d: Duration, steps: u64) -> f64 {
    d.as_secs_f64() * 1e3 / steps.max(1) as f64
}

/// GPU busy time of a profile: the union of its outermost scopes, and the part of
/// it spent in CBPT's uploads and downloads.
fn gpu_busy(profile: &ProfileLog) -> (f64, f64) {
    let mut spans: Vec<(f64, f64)> = profile
        .records
        .iter()
        .filter(|r| r.depth == 0)
        .map(|r| (r.start_ns, r.end_ns))
        .collect();
    spans.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut busy, mut end) = (0.0, f64::NEG_INFINITY);
    for (s, e) in spans {
        if e > end {
            busy += e - s.max(end);
            end = e;
        }
    }
    let transfers: f64 = profile
        .records
        .iter()
        .filter(|r| r.name == "cbpt upload" || r.name == "cbpt download")
        .map(|r| r.end_ns - r.start_ns)
        .sum();
    (busy * 1e-6, transfers * 1e-6)
}

/// The CBPT options of the bench.
fn cbpt_options(options: &CbptBenchOptions, settings: CbptSettings) -> CbptOptions {
    CbptOptions {
        seed: options.seed,
        max_depth: options.max_depth,
        rr_depth: 5,
        settings,
        pipelined: true,
    }
}

/// A CBPT integrator with its GPU combination through `tracer` (or on the CPU).
fn cbpt_integrator(
    gpu: &Gpu,
    scene: &Scene,
    options: &CbptBenchOptions,
    settings: CbptSettings,
    tracer: TracerKind,
) -> Result<CbptIntegrator, RenderError> {
    let frame = scene.camera.frame(options.width, options.height);
    let device = match settings.combination {
        Combination::Gpu => {
            let pt = crate::integrator::pt::PtScene::new(scene);
            Some((gpu, tracer.create(gpu, &pt.triangles)?))
        }
        Combination::Cpu => None,
    };
    let o = cbpt_options(options, settings);
    Ok(CbptIntegrator::new(scene, &frame, &o, device)?)
}

/// One population couple of the paper's sizes on the bench film: its tables.
fn sample_tables(scene: &Scene, options: &CbptBenchOptions) -> Result<Tables, RenderError> {
    let frame = scene.camera.frame(options.width, options.height);
    let o = cbpt_options(options, CbptSettings::default());
    let nl = o.settings.light_paths;
    let setup = Setup::new(CpuScene::new(scene), &frame, &o, 2000, nl)?;
    let cpu = setup.cpu_side();
    let positions = ImagePositions::new(options.width * options.height, 0, setup.streams.shuffle);
    let id = setup.steps(0..1)[0].clone();
    let population = Population::sample(&cpu.sampling, id, &positions, &mut Counters::default());
    Ok(Tables::new(&population))
}

/// The GPU's combination data against the CPU's, by the rules the tests use
/// ([`compare`]), summed over the tracers checked.
#[derive(Clone, Copy, Debug, Default)]
struct Check {
    visibility_bits: u64,
    shading_mismatches: u64,
    /// Tuples along a tangent plane that agree on f alone (not mismatches).
    shading_tangent: u64,
}

impl Check {
    fn of(gpu: &CombinationData, cpu: &CombinationData, tables: &Tables) -> Self {
        let shading = [
            (&gpu.camera, &cpu.camera, compare::End::Camera),
            (&gpu.light, &cpu.light, compare::End::Light),
        ]
        .map(|(g, c, end)| compare::compare_shading(g, c, tables, end));
        Self {
            visibility_bits: compare::visibility_differences(gpu, cpu),
            shading_mismatches: shading.iter().map(|c| c.mismatches() as u64).sum(),
            shading_tangent: shading.iter().map(|c| c.tangent as u64).sum(),
        }
    }

    fn add(self, other: Check) -> Check {
        Check {
            visibility_bits: self.visibility_bits + other.visibility_bits,
            shading_mismatches: self.shading_mismatches + other.shading_mismatches,
            shading_tangent: self.shading_tangent + other.shading_tangent,
        }
    }
}

fn kinds_of(kind: usize) -> Kinds {
    Kinds {
        visibility: kind == 0,
        camera: kind == 1,
        light: kind == 2,
    }
}

/// Seconds of one GPU combination of `kinds` (upload, batches, downloads).
fn time_gpu(c: &mut GpuCombiner, tables: &Arc<Tables>, kinds: Kinds) -> Result<f64, RenderError> {
    c.kinds = kinds;
    let t = Instant::now();
    let pending = c.start(tables.clone())?;
    c.finish(pending)?;
    Ok(t.elapsed().as_secs_f64())
}

/// Table 1 for `tracer` (visibility rows of every tracer, shading rows of the first).
fn throughput(
    gpu: &Gpu,
    cpu_scene: &CpuScene,
    tables: &Arc<Tables>,
    tracer: TracerKind,
    shading: bool,
    rounds: u32,
) -> Result<(Vec<ThroughputRow>, Check), RenderError> {
    let t = tracer.create(gpu, &cpu_scene.tables.triangles)?;
    let mut c = GpuCombiner::new(
        gpu,
        t,
        cpu_scene,
        crate::integrator::cbpt::options::DEFAULT_BATCH,
    )?;
    // Warm-up (lavapipe compiles each kernel at its first dispatch) and the check.
    let pending = c.start(tables.clone())?;
    let data = c.finish(pending)?;
    let checked = Check::of(&data, &evaluate(cpu_scene, tables, Kinds::ALL), tables);
    if checked.visibility_bits > 0 || checked.shading_mismatches > 0 {
        return Err(crate::vk::VkError::Usage(format!(
            "bench cbpt: {tracer}: the GPU's combination data differ from the CPU twins' \
             ({} visibility bits, {} shading tuples); not timing it",
            checked.visibility_bits, checked.shading_mismatches
        ))
        .into());
    }
    let mut rows = Vec::new();
    for kind in 0..if shading { 3 } else { 1 } {
        let (mut g, mut p) = (Vec::new(), Vec::new());
        for _ in 0..rounds.max(1) {
            g.push(time_gpu(&mut c, tables, kinds_of(kind))?);
            let t = Instant::now();
            evaluate(cpu_scene, tables, kinds_of(kind));
            p.push(t.elapsed().as_secs_f64());
        }
        let segments = if kind == 2 {
            tables.light_segments()
        } else {
            tables.segments()
        };
        let rate = |s: f64| segments as f64 / s * 1e-6;
        rows.push(ThroughputRow {
            kind: ["visibility", "camera shading", "light shading"][kind].into(),
            tracer: (kind == 0).then(|| tracer.name().to_string()),
            segments,
            gpu: rate(median(g, EvenMedian::Mean)),
            cpu: rate(median(p, EvenMedian::Mean)),
        });
    }
    Ok((rows, checked))
}

/// Fig. 6: visibility and camera-shading throughput per batch size.
fn batch_sweep(
    gpu: &Gpu,
    cpu_scene: &CpuScene,
    tables: &Arc<Tables>,
    options: &CbptBenchOptions,
) -> Result<Vec<BatchRow>, RenderError> {
    let mut rows = Vec::new();
    for &batch in &options.batches {
        let tracer = options.tracers[0].create(gpu, &cpu_scene.tables.triangles)?;
        let mut c = GpuCombiner::new(gpu, tracer, cpu_scene, batch)?;
        time_gpu(&mut c, tables, Kinds::ALL)?;
        let mut rate = |kind: usize| -> Result<f64, RenderError> {
            let t: Vec<f64> = (0..options.rounds.max(1))
                .map(|_| time_gpu(&mut c, tables, kinds_of(kind)))
                .collect::<Result<_, _>>()?;
            Ok(tables.segments() as f64 / median(t, EvenMedian::Mean) * 1e-6)
        };
        rows.push(BatchRow {
            batch,
            visibility: rate(0)?,
            shading: rate(1)?,
        });
    }
    Ok(rows)
}

/// A contestant of Table 3: CBPT run by blocks of steps, or `bpt` by passes.
enum Contestant {
    Cbpt {
        name: String,
        integrator: Box<CbptIntegrator>,
        next_pass: u32,
    },
    Bpt(Box<BptIntegrator>, u32),
}

impl Contestant {
    fn name(&self) -> String {
        match self {
            Self::Cbpt { name, .. } => name.clone(),
            Self::Bpt(..) => "bpt (CPU)".into(),
        }
    }

    /// One block: CBPT's `steps` steps, or passes of `bpt` for at least `seconds`;
    /// (basic contributions, seconds).
    fn block(&mut self, steps: u32, seconds: f64) -> Result<(u64, f64), RenderError> {
        let t = Instant::now();
        let basic = match self {
            Self::Cbpt {
                integrator,
                next_pass,
                ..
            } => {
                let (setup, backend) = integrator.backend_mut();
                let mut list = setup.steps(*next_pass..*next_pass + 1);
                list.truncate(steps as usize);
                *next_pass += 1;
                backend
                    .run(setup, list, true, &|| false)?
                    .counters
                    .basic_contributions
            }
            Self::Bpt(b, pass) => {
                let before = b.counters().basic_contributions;
                loop {
                    b.render_passes(*pass, 1)?;
                    *pass += 1;
                    if t.elapsed().as_secs_f64() >= seconds {
                        break;
                    }
                }
                b.counters().basic_contributions - before
            }
        };
        Ok((basic, t.elapsed().as_secs_f64()))
    }
}

fn contributions(
    gpu: &Gpu,
    scene: &Scene,
    options: &CbptBenchOptions,
) -> Result<Vec<ContributionRow>, RenderError> {
    let tracer = options.tracers[0];
    let with = |light_traced, combination| CbptSettings {
        light_traced,
        combination,
        ..Default::default()
    };
    let mut contestants = Vec::new();
    for (name, settings) in [
        ("cbpt N_T = 0", with(0, Combination::Gpu)),
        ("cbpt N_T = 1500", with(1500, Combination::Gpu)),
        (
            "cbpt N_T = 1500, CPU combination",
            with(1500, Combination::Cpu),
        ),
    ] {
        let integrator = cbpt_integrator(gpu, scene, options, settings, tracer)?;
        let mut c = Contestant::Cbpt {
            name: name.into(),
            integrator: Box::new(integrator),
            next_pass: 0,
        };
        c.block(1, 0.0)?; // warm-up
        contestants.push((c, Vec::new(), 0.0));
    }
    let frame = scene.camera.frame(options.width, options.height);
    let bpt_options = BptOptions {
        seed: options.seed,
        max_depth: options.max_depth,
        ..Default::default()
    };
    let mut bpt = Contestant::Bpt(
        Box::new(BptIntegrator::new(
            BidirMode::Bpt,
            scene,
            &frame,
            &bpt_options,
        )),
        0,
    );
    bpt.block(1, 0.0)?;
    contestants.push((bpt, Vec::new(), 0.0));
    let n = contestants.len();
    // bpt's blocks last as long as the CBPT block before them.
    let mut last = 0.0;
    for round in 0..options.rounds.max(1) as usize {
        for k in 0..n {
            let (c, rates, seconds) = &mut contestants[(round + k) % n];
            let (basic, s) = c.block(options.steps, last)?;
            rates.push(basic as f64 / s);
            *seconds += s;
            last = s;
        }
    }
    Ok(contestants
        .into_iter()
        .map(|(c, rates, seconds)| ContributionRow {
            name: c.name(),
            per_second: median(rates, EvenMedian::Mean),
            seconds,
        })
        .collect())
}

/// Algorithm 2: blocks of steps pipelined and synchronous, alternating.
fn step_parts(
    gpu: &Gpu,
    scene: &Scene,
    options: &CbptBenchOptions,
) -> Result<Vec<StepRow>, RenderError> {
    let mut integrator = cbpt_integrator(
        gpu,
        scene,
        options,
        CbptSettings::default(),
        options.tracers[0],
    )?;
    let (setup, backend) = integrator.backend_mut();
    // Steps repeat once these are used up: the same work, timed again.
    let steps = setup.steps(0..4);
    let mut next = 0usize;
    let mut block = |pipelined: bool, n: usize| -> Result<(StepTimes, ProfileLog), RenderError> {
        gpu.wait_idle()?;
        let _ = gpu.take_profile();
        let list: Vec<_> = (0..n)
            .map(|k| steps[(next + k) % steps.len()].clone())
            .collect();
        next += n;
        let out = backend_run(backend, setup, list, pipelined)?;
        gpu.wait_idle()?;
        Ok((out, gpu.take_profile()))
    };
    block(true, 2)?; // warm-up
    let mut rows = [StepRow::default(), StepRow::default()];
    for round in 0..options.rounds.max(1) {
        for k in 0..2 {
            let pipelined = (round as usize + k) % 2 == 0;
            let (t, profile) = block(pipelined, options.steps as usize)?;
            let (busy, transfers) = gpu_busy(&profile);
            let row = &mut rows[!pipelined as usize];
            let s = t.steps;
            row.steps += s;
            row.sample += ms(t.sample, 1);
            row.pack += ms(t.pack, 1);
            row.light_tracing += ms(t.light_tracing, 1);
            row.combine += ms(t.combine, 1);
            row.cpu_waiting += ms(t.wait, 1);
            row.submit += ms(t.start, 1);
            row.finish += ms(t.finish, 1);
            row.gpu += busy;
            row.gpu_transfers += transfers;
            row.wall += ms(t.wall, 1);
        }
    }
    for (row, mode) in rows.iter_mut().zip(["pipelined", "synchronous"]) {
        row.mode = mode.into();
        let n = row.steps.max(1) as f64;
        for v in [
            &mut row.sample,
            &mut row.pack,
            &mut row.light_tracing,
            &mut row.combine,
            &mut row.cpu_waiting,
            &mut row.submit,
            &mut row.finish,
            &mut row.gpu,
            &mut row.gpu_transfers,
            &mut row.wall,
        ] {
            *v /= n;
        }
    }
    Ok(rows.to_vec())
}

fn backend_run(
    backend: &mut Backend,
    setup: &Setup,
    steps: Vec<crate::integrator::cbpt::steps::StepId>,
    pipelined: bool,
) -> Result<StepTimes, RenderError> {
    Ok(backend.run(setup, steps, pipelined, &|| false)?.times)
}

/// Runs the benchmark (see the module docs).
pub fn run(
    gpu: &Gpu,
    scene: &Scene,
    options: &CbptBenchOptions,
) -> Result<CbptBenchReport, RenderError> {
    if options.tracers.is_empty() {
        return Err(RenderError::Options("bench cbpt needs a tracer".into()));
    }
    let tables = Arc::new(sample_tables(scene, options)?);
    let cpu_scene = CpuScene::new(scene);
    let mut throughput_rows = Vec::new();
    let mut checked = Check::default();
    for (k, &tracer) in options.tracers.iter().enumerate() {
        let (rows, c) = throughput(gpu, &cpu_scene, &tables, tracer, k == 0, options.rounds)?;
        throughput_rows.extend(rows);
        checked = checked.add(c);
    }
    let batches = batch_sweep(gpu, &cpu_scene, &tables, options)?;
    let contributions = contributions(gpu, scene, options)?;
    let steps = step_parts(gpu, scene, options)?;
    let equal_time = match &options.reference {
        Some(reference) => Some(bdpt_bench::run(
            gpu,
            scene,
            &BdptBenchOptions {
                width: options.width,
                height: options.height,
                integrators: vec![
                    IntegratorKind::Pt,
                    IntegratorKind::Bpt,
                    IntegratorKind::Cbpt,
                ],
                seconds: options.seconds,
                rounds: options.rounds.max(1),
                max_depth: options.max_depth,
                seed: options.seed,
                reference: Some(reference.clone()),
                tracer: Some(options.tracers[0]),
                ..Default::default()
            },
        )?),
        None => None,
    };
    Ok(CbptBenchReport {
        date: super::today(),
        device: device_description(gpu),
        cpu: super::host::cpu_model(),
        threads: rayon::current_num_threads(),
        scene: scene.name.clone(),
        triangles: scene.triangles.len(),
        width: options.width,
        height: options.height,
        tracer: options.tracers[0].name().into(),
        population: format!(
            "N_C 2000, N_L 15: {} camera and {} light vertices ({} on surfaces), {} segments",
            tables.camera.len(),
            tables.light.len(),
            tables.light_surface,
            tables.segments()
        ),
        visibility_mismatches: checked.visibility_bits,
        shading_mismatches: checked.shading_mismatches,
        shading_tangent: checked.shading_tangent,
        throughput: throughput_rows,
        batches,
        contributions,
        steps,
        equal_time,
    })
}

impl CbptBenchReport {
    fn write_header(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "bench cbpt {} ({} triangles) {}x{}, tracer {}, on {} and {} ({} threads), {}",
            self.scene,
            self.triangles,
            self.width,
            self.height,
            self.tracer,
            self.device,
            self.cpu,
            self.threads,
            self.date
        )?;
        writeln!(f, "population: {}", self.population)?;
        writeln!(
            f,
            "check: GPU against CPU combination data: {} visibility bits and {} shading \
             tuples differ ({} along a tangent plane agree on f alone)",
            self.visibility_mismatches, self.shading_mismatches, self.shading_tangent
        )
    }

    fn write_throughput(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "\ncombination throughput (Table 1), millions per second")?;
        writeln!(f, "{:<30} {:>10} {:>10} {:>8}", "", "GPU", "CPU", "GPU/CPU")?;
        for r in &self.throughput {
            let name = match &r.tracer {
                Some(t) => format!("{} ({t})", r.kind),
                None => r.kind.clone(),
            };
            writeln!(
                f,
                "{name:<30} {:>10.3} {:>10.3} {:>8.2}",
                r.gpu,
                r.cpu,
                r.gpu / r.cpu
            )?;
        }
        Ok(())
    }

    fn write_batches(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "\nbatch size (Fig. 6), millions per second on the GPU")?;
        writeln!(
            f,
            "{:>10} {:>12} {:>16}",
            "batch", "visibility", "camera shading"
        )?;
        for r in &self.batches {
            writeln!(
                f,
                "{:>10} {:>12.3} {:>16.3}",
                r.batch, r.visibility, r.shading
            )?;
        }
        Ok(())
    }

    fn write_contributions(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "\nbasic contributions per second (Table 3)")?;
        let bpt = self
            .contributions
            .iter()
            .find(|r| r.name.starts_with("bpt"))
            .map(|r| r.per_second);
        for r in &self.contributions {
            let ratio = bpt.map_or(String::new(), |b| {
                format!(" ({:.2}x bpt)", r.per_second / b)
            });
            writeln!(
                f,
                "{:<36} {:>8.3} M/s{ratio}   [{:.1} s]",
                r.name,
                r.per_second * 1e-6,
                r.seconds
            )?;
        }
        Ok(())
    }

    fn write_steps(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "\na step's parts (Algorithm 2), ms per step")?;
        writeln!(
            f,
            "{:<12} {:>7} {:>7} {:>7} {:>8} {:>8} {:>7} {:>7} {:>7} {:>9} {:>7}",
            "",
            "sample",
            "pack",
            "lt",
            "combine",
            "waiting",
            "submit",
            "finish",
            "GPU",
            "transfer",
            "wall"
        )?;
        for r in &self.steps {
            writeln!(
                f,
                "{:<12} {:>7.2} {:>7.2} {:>7.2} {:>8.2} {:>8.2} {:>7.2} {:>7.2} {:>7.2} {:>9.2} {:>7.2}",
                r.mode,
                r.sample,
                r.pack,
                r.light_tracing,
                r.combine,
                r.cpu_waiting,
                r.submit,
                r.finish,
                r.gpu,
                r.gpu_transfers,
                r.wall
            )?;
        }
        Ok(())
    }

    /// How much of a step the pipelined mode hides, from its two rows (pipelined, then
    /// synchronous).
    fn write_pipelining(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [p, s] = self.steps.as_slice() else {
            return Ok(());
        };
        // The CPU thread's work, and the combination's: the GPU's busy time, or the
        // driver's host time where submissions run to completion (lavapipe).
        let cpu = p.sample + p.pack + p.light_tracing + p.combine;
        let device = p.gpu.max(p.submit + p.finish);
        let hidden = (cpu + device - p.wall) / cpu.min(device).max(1e-9);
        writeln!(
            f,
            "pipelining: {:.2} ms per step against {:.2} synchronous ({:.2}x); per step the \
             CPU works {cpu:.2} ms and the combination takes {device:.2} (GPU busy {:.2}, \
             driver {:.2}): {:.0}% of the shorter hidden behind the longer",
            p.wall,
            s.wall,
            s.wall / p.wall,
            p.gpu,
            p.submit + p.finish,
            100.0 * hidden
        )
    }

    fn write_equal_time(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Some(e) = &self.equal_time else {
            return Ok(());
        };
        writeln!(f, "\nequal time\n{e}")?;
        let row = |k: &str| e.rows.iter().find(|r| r.integrator == k);
        let efficiency = |k: &str| Some(row(k)?.comparable_mse()? * row(k)?.seconds);
        for other in ["pt", "bpt"] {
            if let (Some(c), Some(o)) = (efficiency("cbpt"), efficiency(other)) {
                writeln!(f, "relative MSE x seconds, cbpt / {other}: {:.3}", c / o)?;
            }
        }
        Ok(())
    }
}

impl fmt::Display for CbptBenchReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_header(f)?;
        self.write_throughput(f)?;
        self.write_batches(f)?;
        self.write_contributions(f)?;
        self.write_steps(f)?;
        self.write_pipelining(f)?;
        self.write_equal_time(f)
    }
}
