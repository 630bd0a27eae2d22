//! `splitray bench bdpt SCENE`: integrators at equal wall time, in one run.
//!
//! Every integrator gets the same time, in [`BdptBenchOptions::rounds`] slices taken in
//! turn (the order rotates every round), so that a change of load on a shared machine
//! hits them alike. Each slice renders whole passes until its time is up and continues
//! the integrator's film, so the films at the end are equal-time renders; an integrator
//! that batches passes (`passes_per_call`) gets as many per call as the time left holds
//! at its latest rate. Reported per
//! integrator: samples/s, Mrays/s and, for `bpt` and `light`, CBPT's throughput measure
//! (basic contributions f_{i,j} per second, §6.2) — medians over the slices — and,
//! given a reference, the relative MSE of the final film and its ratio to `pt`'s — with
//! the reference's own noise taken out where its standard errors are known
//! ([`Reference`]: near that floor raw ratios tend to 1 whatever the films). Then
//! the light-vertex-cache integrators at equal samples per pixel, with one stream and
//! three, sorted or not ([`super::lvc`]).

use std::fmt;
use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;

use super::{median, EvenMedian};
use crate::film::{FilmSums, Reference};
use crate::integrator::lvc::Resampling;
use crate::integrator::{Integrator, IntegratorKind};
use crate::render::{create_integrator, device_description, RenderError, RenderOptions};
use crate::scene::Scene;
use crate::vk::Gpu;

#[derive(Clone, Debug)]
pub struct BdptBenchOptions {
    pub width: u32,
    pub height: u32,
    pub integrators: Vec<IntegratorKind>,
    /// Seconds each integrator renders in all.
    pub seconds: f64,
    /// Slices per integrator.
    pub rounds: u32,
    pub max_depth: i32,
    pub seed: u64,
    /// A reference image of this film size.
    pub reference: Option<Arc<Reference>>,
    /// The tracer of the GPU integrators (`None`: the scene's, else the default).
    pub tracer: Option<crate::trace::TracerKind>,
    /// `cis-lbdpt` once per resampling listed (named `cis-lbdpt` with the default's,
    /// `cis-lbdpt independent` with independent draws).
    pub resampling: Vec<Resampling>,
    /// The equal-spp comparison of `lvc-bdpt` and `cis-lbdpt` (passes 0: none).
    pub equal_spp: super::lvc::SppPlan,
}

impl Default for BdptBenchOptions {
    fn default() -> Self {
        Self {
            width: 160,
            height: 120,
            integrators: vec![
                IntegratorKind::Pt,
                IntegratorKind::Bpt,
                IntegratorKind::Light,
                IntegratorKind::LvcBdpt,
                IntegratorKind::CisLbdpt,
            ],
            seconds: 30.0,
            rounds: 10,
            max_depth: -1,
            seed: 0,
            reference: None,
            tracer: None,
            resampling: vec![Resampling::default()],
            equal_spp: Default::default(),
        }
    }
}

/// One integrator's figures.
#[derive(Clone, Debug, Serialize)]
pub struct BdptRow {
    pub integrator: String,
    pub seconds: f64,
    pub passes: u32,
    /// Median over the slices of pixel samples per second.
    pub samples_per_second: f64,
    /// Median over the slices of rays per second, in millions.
    pub mrays_per_second: f64,
    /// Median over the slices of basic contributions per second (bpt, light).
    pub basic_contributions_per_second: Option<f64>,
    /// Against the reference, as it is.
    pub relative_mse: Option<f64>,
    /// `relative_mse` less the reference's own noise (where its standard errors are
    /// known): the film's error against the reference's expectation.
    pub relative_mse_excess: Option<f64>,
}

impl BdptRow {
    /// The error integrators are compared by: without the reference's noise where that
    /// is known (`None` if the film's error is inside it), else as measured.
    pub fn comparable_mse(&self) -> Option<f64> {
        crate::film::ReferenceError {
            relative_mse: self.relative_mse?,
            excess: self.relative_mse_excess,
        }
        .comparable()
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct BdptBenchReport {
    pub date: String,
    pub device: String,
    pub cpu: String,
    pub threads: usize,
    pub scene: String,
    pub triangles: usize,
    pub width: u32,
    pub height: u32,
    pub max_depth: i32,
    pub seconds_each: f64,
    pub rounds: u32,
    pub reference: Option<String>,
    /// The relative MSE the reference's own noise adds to every film's (from its
    /// standard errors), taken out of the ratios.
    pub reference_noise: Option<f64>,
    pub rows: Vec<BdptRow>,
    /// `lvc-bdpt` and `cis-lbdpt` at equal spp, with 1 and 3 streams.
    pub equal_spp: Vec<super::lvc::SppRow>,
}

impl BdptBenchReport {
    /// relative MSE of `kind` over `pt`'s, when both were measured against a reference
    /// (without its noise, where known: [`BdptRow::comparable_mse`]).
    pub fn mse_ratio_to_pt(&self, kind: &str) -> Option<f64> {
        let mse = |k: &str| {
            self.rows
                .iter()
                .find(|r| r.integrator == k)?
                .comparable_mse()
        };
        Some(mse(kind)? / mse("pt")?)
    }
}

impl fmt::Display for BdptBenchReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "bench bdpt {} ({} triangles) {}x{} max_depth {}, {:.1} s each in {} slices, on {} \
             and {} ({} threads), {}",
            self.scene,
            self.triangles,
            self.width,
            self.height,
            self.max_depth,
            self.seconds_each,
            self.rounds,
            self.device,
            self.cpu,
            self.threads,
            self.date
        )?;
        if let Some(r) = &self.reference {
            writeln!(f, "reference: {r}")?;
        }
        if let Some(noise) = self.reference_noise {
            writeln!(
                f,
                "the reference's own noise adds {noise:.4e} to each relative MSE (from its \
                 standard errors); \"excess\" and the ratios are without it"
            )?;
        }
        let w = self
            .rows
            .iter()
            .map(|r| r.integrator.len())
            .max()
            .unwrap_or(0)
            .max(8);
        writeln!(
            f,
            "{:<w$} {:>8} {:>7} {:>12} {:>9} {:>16} {:>12} {:>12}",
            "",
            "seconds",
            "passes",
            "samples/s",
            "Mrays/s",
            "basic contrib/s",
            "rel. MSE",
            "excess"
        )?;
        for r in &self.rows {
            let basic = r
                .basic_contributions_per_second
                .map_or("-".to_string(), |b| format!("{b:.4e}"));
            let figure = |m: Option<f64>| m.map_or("-".to_string(), |m| format!("{m:.4e}"));
            writeln!(
                f,
                "{:<w$} {:>8.2} {:>7} {:>12.0} {:>9.3} {:>16} {:>12} {:>12}",
                r.integrator,
                r.seconds,
                r.passes,
                r.samples_per_second,
                r.mrays_per_second,
                basic,
                figure(r.relative_mse),
                figure(r.relative_mse_excess)
            )?;
        }
        for r in &self.rows {
            if r.relative_mse_excess.is_some_and(|e| e <= 0.0) {
                writeln!(
                    f,
                    "{}: error inside the reference's noise, no ratio",
                    r.integrator
                )?;
            }
        }
        for r in &self.rows {
            if r.integrator != "pt" {
                if let Some(ratio) = self.mse_ratio_to_pt(&r.integrator) {
                    writeln!(f, "relative MSE {} / pt: {ratio:.3}", r.integrator)?;
                }
            }
        }
        let row = |k: &str| self.rows.iter().find(|r| r.integrator == k);
        let mse = |k: &str| row(k)?.comparable_mse();
        let cis_rows = self
            .rows
            .iter()
            .filter(|r| r.integrator.starts_with("cis-lbdpt"));
        for cis_row in cis_rows {
            let name = &cis_row.integrator;
            let (Some(cis), Some(lvc)) = (cis_row.comparable_mse(), mse("lvc-bdpt")) else {
                continue;
            };
            writeln!(f, "relative MSE {name} / lvc-bdpt: {:.3}", cis / lvc)?;
            // A slice's last call can overrun it (its pass count comes from the previous
            // call's rate), and an unbiased estimate's MSE falls as 1 / time: MSE × seconds
            // compares the two at exactly equal time.
            let seconds = |k: &str| row(k).map_or(1.0, |r| r.seconds);
            writeln!(
                f,
                "relative MSE × seconds {name} / lvc-bdpt: {:.3}",
                cis * seconds(name) / (lvc * seconds("lvc-bdpt"))
            )?;
        }
        super::lvc::write_equal_spp(f, &self.equal_spp)
    }
}

/// One integrator under measurement.
struct Contestant {
    kind: IntegratorKind,
    /// The row's name: the integrator's, and its resampling where that is not the
    /// default.
    label: String,
    integrator: Box<dyn Integrator>,
    next_pass: u32,
    /// Seconds per pass of the latest call, which sizes the next one.
    pass_seconds: Option<f64>,
    seconds: f64,
    passes: u32,
    samples: Vec<f64>,
    rays: Vec<f64>,
    basic: Vec<f64>,
}

fn counter(i: &dyn Integrator, name: &str) -> u64 {
    i.stats().counters.get(name).copied().unwrap_or(0)
}

impl Contestant {
    fn new(
        gpu: &Gpu,
        scene: &Scene,
        options: &RenderOptions,
        label: String,
    ) -> Result<Self, RenderError> {
        let mut integrator = create_integrator(gpu, scene, options)?;
        // Warm-up (lavapipe compiles each kernel at its first dispatch), then an empty
        // film: the measured passes continue from pass 1.
        integrator.render_passes(0, 1)?;
        let per_pass = integrator.samples_per_pass();
        let empty = FilmSums::new(options.width, options.height, per_pass, true);
        integrator.restore(&empty)?;
        Ok(Self {
            kind: options.integrator,
            label,
            integrator,
            next_pass: 1,
            pass_seconds: None,
            seconds: 0.0,
            passes: 0,
            samples: Vec::new(),
            rays: Vec::new(),
            basic: Vec::new(),
        })
    }

    /// Renders passes for `slice` seconds (at least one) and records the slice's rates.
    fn run_slice(&mut self, slice: f64, pixels: f64) -> Result<(), RenderError> {
        let rays0 = self.integrator.stats().rays_traced;
        let basic0 = counter(self.integrator.as_ref(), "basic_contributions");
        let start = Instant::now();
        let mut passes = 0u32;
        while passes == 0 || start.elapsed().as_secs_f64() < slice {
            // As many passes per call as fit in the time left by the latest call's rate
            // (at least one, at most what the integrator batches), so that integrators
            // that batch passes into one wavefront do so without overrunning the slice.
            let left = slice - start.elapsed().as_secs_f64();
            let count = self.pass_seconds.map_or(1, |t| {
                ((left / t.max(1e-9)).floor() as u32).clamp(1, self.integrator.passes_per_call())
            });
            let call = Instant::now();
            self.integrator.render_passes(self.next_pass, count)?;
            self.pass_seconds = Some(call.elapsed().as_secs_f64() / count as f64);
            self.next_pass += count;
            passes += count;
        }
        let t = start.elapsed().as_secs_f64().max(1e-9);
        self.seconds += t;
        self.passes += passes;
        let per_pass = self.integrator.samples_per_pass() as f64;
        self.samples.push(passes as f64 * per_pass * pixels / t);
        self.rays
            .push((self.integrator.stats().rays_traced - rays0) as f64 / t);
        let basic = counter(self.integrator.as_ref(), "basic_contributions") - basic0;
        self.basic.push(basic as f64 / t);
        Ok(())
    }
}

/// Runs the benchmark (see the module docs).
pub fn run(
    gpu: &Gpu,
    scene: &Scene,
    options: &BdptBenchOptions,
) -> Result<BdptBenchReport, RenderError> {
    let rounds = options.rounds.max(1);
    let mut contestants = Vec::new();
    for &kind in &options.integrators {
        let mut o = RenderOptions::resolve(
            scene,
            Some(options.width),
            Some(options.height),
            Some(u32::MAX),
            Some(options.seed),
            Some(kind),
            options.tracer,
        )?;
        o.max_depth = options.max_depth;
        if kind != IntegratorKind::CisLbdpt {
            contestants.push(Contestant::new(gpu, scene, &o, kind.name().into())?);
            continue;
        }
        for (k, &resampling) in options.resampling.iter().enumerate() {
            if options.resampling[..k].contains(&resampling) {
                continue;
            }
            o.lvc.resampling = Some(resampling);
            let label = if resampling == Resampling::default() {
                kind.name().to_string()
            } else {
                format!("{} {}", kind.name(), resampling.name())
            };
            contestants.push(Contestant::new(gpu, scene, &o, label)?);
        }
    }
    let slice = options.seconds / rounds as f64;
    let pixels = options.width as f64 * options.height as f64;
    let n = contestants.len();
    for round in 0..rounds as usize {
        for k in 0..n {
            contestants[(round + k) % n].run_slice(slice, pixels)?;
        }
    }
    let mut rows = Vec::new();
    for c in &mut contestants {
        let mean = c.integrator.sums()?.mean();
        let error = options.reference.as_ref().and_then(|r| r.error(&mean));
        let bidirectional = matches!(
            c.kind,
            IntegratorKind::Bpt | IntegratorKind::Light | IntegratorKind::Cbpt
        );
        rows.push(BdptRow {
            integrator: c.label.clone(),
            seconds: c.seconds,
            passes: c.passes,
            samples_per_second: median(c.samples.iter().copied(), EvenMedian::Mean),
            mrays_per_second: median(c.rays.iter().copied(), EvenMedian::Mean) * 1e-6,
            basic_contributions_per_second: bidirectional
                .then(|| median(c.basic.iter().copied(), EvenMedian::Mean)),
            relative_mse: error.map(|e| e.relative_mse),
            relative_mse_excess: error.and_then(|e| e.excess),
        });
    }
    let mut base = RenderOptions::resolve(
        scene,
        Some(options.width),
        Some(options.height),
        None,
        Some(options.seed),
        None,
        None,
    )?;
    base.max_depth = options.max_depth;
    let equal_spp = if options.equal_spp.passes > 0 {
        super::lvc::equal_spp(gpu, scene, &base, &options.integrators, &options.equal_spp)?
    } else {
        Vec::new()
    };
    Ok(BdptBenchReport {
        date: super::today(),
        device: device_description(gpu),
        cpu: super::host::cpu_model(),
        threads: rayon::current_num_threads(),
        scene: scene.name.clone(),
        triangles: scene.triangles.len(),
        width: options.width,
        height: options.height,
        max_depth: options.max_depth,
        seconds_each: options.seconds,
        rounds,
        reference: options.reference.as_ref().map(|r| r.describe()),
        reference_noise: options
            .reference
            .as_ref()
            .and_then(|r| r.own_relative_mse()),
        rows,
        equal_spp,
    })
}
