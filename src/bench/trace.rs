//! `splitray bench trace`: build + trace time per frame for each tracer on one scene and
//! workload, with Mrays/s, peak GPU memory and ratios between tracers, all measured in
//! the same run. Every tracer's hits are checked against brute force on a sample of
//! rays before anything is timed.

use std::fmt;
use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use super::workloads::{self, RayBatch, Workload};
use super::{median, EvenMedian};
use crate::scene::Scene;
use crate::trace::{
    cpu, BruteForceTracer, GpuTriangle, Hit, HostTiming, LevelSplit, PdacrtParams, PdacrtTracer,
    Query, Ray, Tracer, TracerKind,
};
use crate::vk::{self, Buffer, Gpu};

pub type BenchResult<T> = std::result::Result<T, Box<dyn std::error::Error + Send + Sync>>;

#[derive(Clone, Debug)]
pub struct TraceBenchOptions {
    pub width: u32,
    pub height: u32,
    pub workload: Workload,
    pub tracers: Vec<TracerKind>,
    /// Timed frames per tracer (at least 5), after one warm-up frame.
    pub frames: usize,
    /// Brute force traces at most this many ray–triangle tests per frame; beyond it, a
    /// strided subset of the rays is traced and the time extrapolated (marked).
    pub brute_force_budget: f64,
    /// Rays per batch checked against brute force before timing, at most.
    pub verify_rays: usize,
    /// Ray–triangle tests the brute-force check may take per batch: on scenes of
    /// millions of triangles it checks fewer rays (at least 64).
    pub verify_budget: f64,
    /// PDACRT parameters instead of the device defaults.
    pub pdacrt: Option<crate::trace::PdacrtParams>,
}

impl Default for TraceBenchOptions {
    fn default() -> Self {
        Self {
            width: 1024,
            height: 1024,
            workload: Workload::Primary,
            tracers: vec![TracerKind::Pdacrt, TracerKind::BruteForce],
            frames: 5,
            brute_force_budget: 3e8,
            verify_rays: 4096,
            verify_budget: 4e9,
            pdacrt: None,
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct TracerRow {
    pub tracer: String,
    /// Median build + trace time of a frame, in ms (extrapolated when `subset` < 1).
    pub frame_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub mrays_per_s: f64,
    /// Peak GPU memory during a frame, rays and hits included.
    pub peak_gpu_bytes: u64,
    /// The part of the peak that the tracer itself allocated (its triangles, lists,
    /// buffers and acceleration structures): the peak less the rays and hits.
    pub tracer_peak_bytes: u64,
    /// GPU time per kernel over the last frame.
    pub kernels: Vec<vk::KernelTime>,
    /// The last frame's GPU scopes as a tree (total and self times).
    pub profile: vk::ProfileTree,
    /// Fraction of the rays actually traced (1 unless extrapolated).
    pub subset: f64,
    /// Hits checked against brute force before timing, and how many differed.
    pub verified_rays: usize,
    pub mismatches: usize,
    /// Host round trips per frame (PDACRT's level loop), when the tracer counts them.
    pub host_round_trips: Option<u32>,
    pub levels: Option<usize>,
    /// For tracers that trace on the CPU: their build and traversal alone.
    pub host: Option<HostRow>,
}

/// A CPU tracer's own work per frame, GPU buffer transfers excluded (medians over the
/// timed frames).
#[derive(Clone, Debug, Serialize)]
pub struct HostRow {
    /// Building the acceleration structure (`set_geometry`).
    pub build_ms: f64,
    /// The traversals alone.
    pub trace_ms: f64,
    /// Rays per second of the traversals alone.
    pub trace_mrays_per_s: f64,
    /// Threads the traversal ran on (rayon's pool).
    pub threads: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct TraceReport {
    pub scene: String,
    pub triangles: usize,
    pub device: String,
    pub width: u32,
    pub height: u32,
    pub workload: Workload,
    pub batches: Vec<(String, usize)>,
    pub rays: usize,
    pub rows: Vec<TracerRow>,
    /// PDACRT's per-level statistics of its last frame.
    pub pdacrt_levels: Vec<crate::trace::pdacrt::LevelStats>,
    /// The PDACRT parameters it ran with (when it ran).
    pub pdacrt_params: Option<PdacrtParams>,
    pub date: String,
}

impl TraceReport {
    /// The run's scene, workload and device, and the table's column heads.
    fn write_header(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "bench trace: {} ({} triangles), {}x{} {} workload, {} rays in {} batch(es), on {}",
            self.scene,
            self.triangles,
            self.width,
            self.height,
            self.workload,
            self.rays,
            self.batches.len(),
            self.device
        )?;
        writeln!(
            f,
            "{:<12} {:>11} {:>10} {:>10} {:>10} {:>11} {:>11} {:>9}  vs each",
            "tracer", "frame ms", "min ms", "max ms", "Mrays/s", "peak MiB", "own MiB", "verified"
        )
    }

    /// A tracer's row: its times, memory and checks, and how much faster it is than
    /// each other tracer.
    fn write_row(&self, f: &mut fmt::Formatter<'_>, r: &TracerRow) -> fmt::Result {
        let ratios: Vec<String> = self
            .rows
            .iter()
            .filter(|o| o.tracer != r.tracer)
            .map(|o| format!("{:.2}x {}", o.frame_ms / r.frame_ms, o.tracer))
            .collect();
        writeln!(
            f,
            "{:<12} {:>11.2} {:>10.2} {:>10.2} {:>10.2} {:>11.1} {:>11.1} {:>9}{}{}",
            r.tracer,
            r.frame_ms,
            r.min_ms,
            r.max_ms,
            r.mrays_per_s,
            r.peak_gpu_bytes as f64 / (1 << 20) as f64,
            r.tracer_peak_bytes as f64 / (1 << 20) as f64,
            format!("{}/{}", r.verified_rays - r.mismatches, r.verified_rays),
            match ratios.is_empty() {
                true => String::new(),
                false => format!("  faster than: {}", ratios.join(", ")),
            },
            if r.subset < 1.0 {
                format!("  [extrapolated from {:.2}% of the rays]", 100.0 * r.subset)
            } else {
                String::new()
            }
        )
    }

    /// PDACRT's share of its row's peak memory: triangles, rays and hits, and its own
    /// working memory.
    fn write_pdacrt_memory(&self, f: &mut fmt::Formatter<'_>, r: &TracerRow) -> fmt::Result {
        let triangles = (self.triangles * size_of::<GpuTriangle>()) as u64;
        let working = r.tracer_peak_bytes.saturating_sub(triangles);
        writeln!(
            f,
            "{:<12} at the peak: triangles {:.1} MiB, rays and hits {:.1} MiB, PDACRT's working memory {:.1} MiB = {:.1}% of the peak",
            "",
            triangles as f64 / (1 << 20) as f64,
            r.peak_gpu_bytes.saturating_sub(r.tracer_peak_bytes) as f64 / (1 << 20) as f64,
            working as f64 / (1 << 20) as f64,
            100.0 * working as f64 / r.peak_gpu_bytes.max(1) as f64
        )
    }
}

/// A CPU tracer's own build and traversal, and what is left of its frame: the transfers.
fn write_host_work(f: &mut fmt::Formatter<'_>, r: &TracerRow, h: &HostRow) -> fmt::Result {
    writeln!(
        f,
        "{:<12} on the host: build {:.2} ms, trace {:.2} ms = {:.2} Mrays/s on {} threads (frame less build and trace: {:.2} ms of ray and hit transfers)",
        "",
        h.build_ms,
        h.trace_ms,
        h.trace_mrays_per_s,
        h.threads,
        (r.frame_ms - h.build_ms - h.trace_ms).max(0.0)
    )
}

/// The PDACRT parameters of the run.
fn write_pdacrt_params(f: &mut fmt::Formatter<'_>, p: &PdacrtParams) -> fmt::Result {
    writeln!(
        f,
        "{:<12} α {} β {} η {} λ {} N {} T {}, chunks of {} rays, split {}, flush {:?}, triangles {}, {} boxes, level plan in {}",
        "",
        p.alpha,
        p.beta,
        p.eta,
        p.lambda,
        p.intersect_workgroup,
        p.batch,
        p.max_rays_per_chunk,
        match p.split {
            LevelSplit::PrefixSums =>
                format!("PrefixSums (tiles per {} invocations)", p.tile_workgroup),
            split => format!("{split:?}"),
        },
        p.flush_reduce,
        if p.stage_triangles { "staged" } else { "direct" },
        if p.tight_boxes { "tight" } else { "half" },
        if p.one_dispatch_plan { "one dispatch" } else { "four dispatches" }
    )
}

impl fmt::Display for TraceReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_header(f)?;
        for r in &self.rows {
            self.write_row(f, r)?;
            if let Some(h) = &r.host {
                write_host_work(f, r, h)?;
            }
            if let (Some(trips), Some(levels)) = (r.host_round_trips, r.levels) {
                writeln!(
                    f,
                    "{:<12} {levels} levels, {trips} host round trips per frame",
                    ""
                )?;
            }
            if let (true, Some(p)) = (r.tracer == "pdacrt", &self.pdacrt_params) {
                write_pdacrt_params(f, p)?;
                self.write_pdacrt_memory(f, r)?;
            }
        }
        Ok(())
    }
}

struct GpuBatch {
    rays: Buffer,
    hits: Buffer,
    count: u32,
    query: Query,
}

fn strided(rays: &[Ray], count: usize) -> Vec<Ray> {
    if rays.len() <= count {
        return rays.to_vec();
    }
    let step = rays.len() as f64 / count as f64;
    (0..count)
        .map(|i| rays[(i as f64 * step) as usize])
        .collect()
}

/// A tracer in the timed rounds, with what phase 1 measured.
struct Contender {
    kind: TracerKind,
    /// The strided subset brute force traces when the whole workload would be too slow.
    subset_batches: Option<Vec<GpuBatch>>,
    /// Rays of the workload per ray traced (1 unless on a subset).
    scale: f64,
    verified: usize,
    mismatches: usize,
    peak: u64,
    baseline: u64,
    times: Vec<f64>,
    /// Host build and trace times per timed frame (CPU tracers).
    host: Vec<HostTiming>,
    kernels: Vec<vk::KernelTime>,
    profile: vk::ProfileTree,
    tracer: Option<Box<dyn Tracer>>,
}

/// One frame as a dynamic scene would run it: new geometry (PDACRT and the CPU DACRT
/// only take the triangles; ray-query and cpu-bvh rebuild), then every batch. Returns
/// its ms.
fn run_frame(
    gpu: &Gpu,
    tracer: &mut dyn Tracer,
    triangles: &[GpuTriangle],
    batches: &[GpuBatch],
) -> vk::Result<f64> {
    gpu.wait_idle()?;
    let start = Instant::now();
    tracer.set_geometry(triangles)?;
    let mut last = None;
    for b in batches {
        last = Some(tracer.trace(&b.rays, &b.hits, b.count, b.query, &[])?);
    }
    if let Some(p) = last {
        gpu.wait(&p)?;
    }
    let ms = start.elapsed().as_secs_f64() * 1e3;
    gpu.wait_idle()?;
    Ok(ms)
}

fn trace_once(
    gpu: &Gpu,
    tracer: &mut dyn Tracer,
    rays: &[Ray],
    query: Query,
) -> vk::Result<Vec<Hit>> {
    let ray_buf = gpu.upload("bench-rays", rays)?;
    let hit_buf = gpu.create_buffer(
        "bench-hits",
        (rays.len() * size_of::<Hit>()) as u64,
        vk::MemoryKind::Device,
    )?;
    let done = tracer.trace(&ray_buf, &hit_buf, rays.len() as u32, query, &[])?;
    gpu.wait(&done)?;
    hit_buf.read()
}

impl GpuBatch {
    /// `rays` on the device, with a hits buffer of `hit_slots` hits.
    fn upload(gpu: &Gpu, rays: &[Ray], hit_slots: usize, query: Query) -> vk::Result<Self> {
        Ok(Self {
            rays: gpu.upload("bench-rays", rays)?,
            hits: gpu.create_buffer(
                "bench-hits",
                (hit_slots * size_of::<Hit>()) as u64,
                vk::MemoryKind::Device,
            )?,
            count: rays.len() as u32,
            query,
        })
    }
}

/// Per batch, brute force's hits on a strided sample of its rays: (rays, hits, query).
type OracleSamples = Vec<(Vec<Ray>, Vec<Hit>, Query)>;

/// What every step of the benchmark shares: the device, the options, the scene's
/// triangles and the workload, on the host and on the device.
struct Bench<'a> {
    gpu: &'a Gpu,
    opts: &'a TraceBenchOptions,
    triangles: Vec<GpuTriangle>,
    batches: Vec<RayBatch>,
    gpu_batches: Vec<GpuBatch>,
    /// Rays of the whole workload, all batches together.
    total_rays: usize,
}

/// Runs the benchmark. `dump_hits`: once every tracer is verified and timed, write the
/// primary hits there (pixel order; PDACRT's with its default parameters, which make the
/// workload's rays).
pub fn run(
    gpu: &Gpu,
    scene: &Scene,
    opts: &TraceBenchOptions,
    dump_hits: Option<&Path>,
) -> BenchResult<TraceReport> {
    let triangles = scene.gpu_triangles();
    let (batches, primary_hits) = workload_batches(gpu, scene, opts, &triangles)?;
    let bench = Bench::upload(gpu, opts, triangles, batches)?;
    let samples = bench.oracle_samples()?;

    // Phase 1, per tracer alone on the device: verify it, then measure its peak memory
    // over a warm-up frame and one more (its pools persist between frames, so another
    // tracer alive at the same time would blur both figures).
    let mut contenders = Vec::new();
    for &kind in &opts.tracers {
        contenders.push(bench.measure_alone(kind, &samples)?);
    }

    // Phase 2: all tracers together, one warm-up frame each (LLVM compiles each kernel
    // at its first dispatch on lavapipe), then timed frames in interleaved rounds, so
    // that a change of load on a shared machine hits every tracer alike.
    bench.warm_up(&mut contenders)?;
    bench.time_rounds(&mut contenders)?;
    if let Some(path) = dump_hits {
        write_hits(path, &primary_hits)?;
    }
    Ok(bench.report(scene, contenders))
}

/// The workload's rays, from PDACRT's primary hits (checked later like every tracer),
/// and those hits.
fn workload_batches(
    gpu: &Gpu,
    scene: &Scene,
    opts: &TraceBenchOptions,
    triangles: &[GpuTriangle],
) -> BenchResult<(Vec<RayBatch>, Vec<Hit>)> {
    let primary = workloads::primary_rays(scene, opts.width, opts.height);
    let mut reference = PdacrtTracer::new(gpu, triangles)?;
    let primary_hits = trace_once(gpu, &mut reference, &primary, Query::ClosestHit)?;
    if opts.workload == Workload::Primary {
        let batch = RayBatch {
            label: "primary".into(),
            rays: primary,
            query: Query::ClosestHit,
        };
        return Ok((vec![batch], primary_hits));
    }
    let mut trace = |rays: &[Ray]| {
        trace_once(gpu, &mut reference, rays, Query::ClosestHit).expect("trace bounce")
    };
    let batches = workloads::secondary_batches(
        opts.workload,
        scene,
        triangles,
        &primary,
        &primary_hits,
        &mut trace,
    );
    Ok((batches, primary_hits))
}

/// Traces every sample's rays with `tracer`: (rays checked, hits that differ from brute
/// force's).
fn count_mismatches(
    gpu: &Gpu,
    tracer: &mut dyn Tracer,
    samples: &OracleSamples,
) -> vk::Result<(usize, usize)> {
    let (mut verified, mut mismatches) = (0, 0);
    for (rays, want, query) in samples {
        let got = trace_once(gpu, tracer, rays, *query)?;
        verified += rays.len();
        mismatches += got
            .iter()
            .zip(want)
            .filter(|(g, w)| match query {
                Query::ClosestHit => !cpu::same_hit(g, w, 1e-5, true),
                Query::Occlusion => g.is_hit() != w.is_hit(),
            })
            .count();
    }
    Ok((verified, mismatches))
}

impl<'a> Bench<'a> {
    /// Puts every batch's rays on the device, with room for its hits.
    fn upload(
        gpu: &'a Gpu,
        opts: &'a TraceBenchOptions,
        triangles: Vec<GpuTriangle>,
        batches: Vec<RayBatch>,
    ) -> vk::Result<Self> {
        let total_rays: usize = batches.iter().map(|b| b.rays.len()).sum();
        let gpu_batches: Vec<GpuBatch> = batches
            .iter()
            .map(|b| GpuBatch::upload(gpu, &b.rays, b.rays.len().max(1), b.query))
            .collect::<vk::Result<_>>()?;
        Ok(Self {
            gpu,
            opts,
            triangles,
            batches,
            gpu_batches,
            total_rays,
        })
    }

    /// Brute-force samples for verification (the oracle of every tracer): at most
    /// `verify_rays` strided rays per batch, fewer where `verify_budget` says so.
    fn oracle_samples(&self) -> vk::Result<OracleSamples> {
        let mut oracle = BruteForceTracer::new(self.gpu, &self.triangles)?;
        let affordable = (self.opts.verify_budget / self.triangles.len().max(1) as f64) as usize;
        let verify_rays = affordable.clamp(64.min(self.opts.verify_rays), self.opts.verify_rays);
        let samples = self
            .batches
            .iter()
            .map(|b| -> vk::Result<_> {
                let rays = strided(&b.rays, verify_rays);
                let hits = trace_once(self.gpu, &mut oracle, &rays, b.query)?;
                Ok((rays, hits, b.query))
            })
            .collect::<vk::Result<_>>()?;
        drop(oracle);
        Ok(samples)
    }

    /// A new tracer of `kind`, with the options' PDACRT parameters where they give them.
    fn make_tracer(&self, kind: TracerKind) -> vk::Result<Box<dyn Tracer>> {
        match (kind, self.opts.pdacrt) {
            (TracerKind::Pdacrt, Some(params)) => Ok(Box::new(PdacrtTracer::with_params(
                self.gpu,
                &self.triangles,
                params,
            )?)),
            _ => kind.create(self.gpu, &self.triangles),
        }
    }

    /// Phase 1 for one tracer, alone on the device: verifies it against `samples`, then
    /// measures its peak memory. Fails if any sampled hit differs.
    fn measure_alone(&self, kind: TracerKind, samples: &OracleSamples) -> BenchResult<Contender> {
        let mut tracer = self.make_tracer(kind)?;
        // Verify before timing.
        let (verified, mismatches) = count_mismatches(self.gpu, tracer.as_mut(), samples)?;
        if mismatches > 0 {
            return Err(format!("{}: {mismatches} of {verified} sampled hits differ from brute force; not timing it", kind.name()).into());
        }
        let subset_batches = self.brute_force_subset(kind)?;
        let timed = subset_batches.as_deref().unwrap_or(&self.gpu_batches);
        let traced: usize = timed.iter().map(|b| b.count as usize).sum();
        let scale = self.total_rays as f64 / traced.max(1) as f64;

        // Everything on the device before the tracer's first frame: rays, hits and the
        // bench's own buffers (the tracer's pipelines hold no device memory).
        drop(tracer);
        self.gpu.wait_idle()?;
        let baseline = self.gpu.memory_bytes().0;
        let peak = self.peak_memory(kind, timed)?;
        Ok(Contender {
            kind,
            subset_batches,
            scale,
            verified,
            mismatches,
            peak,
            baseline,
            times: Vec::new(),
            host: Vec::new(),
            kernels: Vec::new(),
            profile: Default::default(),
            tracer: None,
        })
    }

    /// Brute force on a subset when the whole frame would take too long (more than
    /// `brute_force_budget` ray–triangle tests): a strided part of each batch. `None` for
    /// every other tracer and for brute force within the budget.
    fn brute_force_subset(&self, kind: TracerKind) -> vk::Result<Option<Vec<GpuBatch>>> {
        let budget = self.opts.brute_force_budget;
        let tests = self.triangles.len() as f64 * self.total_rays as f64;
        let subset = if kind == TracerKind::BruteForce && tests > budget {
            budget / tests
        } else {
            1.0
        };
        if subset < 1.0 {
            let batches = self
                .batches
                .iter()
                .map(|b| -> vk::Result<GpuBatch> {
                    let rays = strided(
                        &b.rays,
                        ((b.rays.len() as f64 * subset).ceil() as usize).max(1),
                    );
                    GpuBatch::upload(self.gpu, &rays, rays.len(), b.query)
                })
                .collect::<vk::Result<Vec<_>>>()?;
            Ok(Some(batches))
        } else {
            Ok(None)
        }
    }

    /// Peak device memory of a fresh tracer of `kind` over a warm-up frame of `timed` and
    /// one more; the tracer is gone and the profile discarded on return.
    fn peak_memory(&self, kind: TracerKind, timed: &[GpuBatch]) -> vk::Result<u64> {
        let gpu = self.gpu;
        let mut tracer = self.make_tracer(kind)?;
        let mut peak = 0;
        for _ in 0..2 {
            gpu.wait_idle()?;
            gpu.reset_peak_memory();
            run_frame(gpu, tracer.as_mut(), &self.triangles, timed)?;
            peak = peak.max(gpu.memory_bytes().1);
        }
        drop(tracer);
        gpu.wait_idle()?;
        let _ = gpu.take_profile();
        Ok(peak)
    }

    /// Phase 2's start: creates every contender's tracer, all alive together, and runs
    /// one warm-up frame of each; the warm-up frames' profile is discarded.
    fn warm_up(&self, contenders: &mut [Contender]) -> vk::Result<()> {
        for c in contenders.iter_mut() {
            let mut tracer = self.make_tracer(c.kind)?;
            let timed = c.subset_batches.as_deref().unwrap_or(&self.gpu_batches);
            run_frame(self.gpu, tracer.as_mut(), &self.triangles, timed)?;
            c.tracer = Some(tracer);
        }
        let _ = self.gpu.take_profile();
        Ok(())
    }

    /// The timed frames: rounds of one frame per contender, in order (at least 5
    /// rounds), each frame's time scaled to the whole workload; the kernels and profile
    /// kept are each contender's last frame's.
    fn time_rounds(&self, contenders: &mut [Contender]) -> vk::Result<()> {
        let gpu = self.gpu;
        for _ in 0..self.opts.frames.max(5) {
            for c in contenders.iter_mut() {
                let timed = c.subset_batches.as_deref().unwrap_or(&self.gpu_batches);
                let tracer = c.tracer.as_deref_mut().expect("created above");
                let ms = run_frame(gpu, tracer, &self.triangles, timed)?;
                c.times.push(ms * c.scale);
                c.host.extend(tracer.host_timing());
                let log = gpu.take_profile();
                c.kernels = log.summary();
                c.profile = log.tree();
            }
            crate::err!(".");
        }
        crate::errln!();
        Ok(())
    }

    /// The report: a row per contender, in the options' order, and PDACRT's per-level
    /// statistics (of the last contender that has them).
    fn report(&self, scene: &Scene, contenders: Vec<Contender>) -> TraceReport {
        let (gpu, opts) = (self.gpu, self.opts);
        let mut rows = Vec::new();
        let mut pdacrt_levels = Vec::new();
        for c in contenders {
            let (row, levels) = c.into_row(self.total_rays);
            if let Some(levels) = levels {
                pdacrt_levels = levels;
            }
            rows.push(row);
        }
        TraceReport {
            scene: scene.name.clone(),
            triangles: self.triangles.len(),
            device: crate::render::device_description(gpu),
            width: opts.width,
            height: opts.height,
            workload: opts.workload,
            batches: self
                .batches
                .iter()
                .map(|b| (b.label.clone(), b.rays.len()))
                .collect(),
            rays: self.total_rays,
            rows,
            pdacrt_levels,
            pdacrt_params: opts
                .tracers
                .contains(&TracerKind::Pdacrt)
                .then(|| opts.pdacrt.unwrap_or_else(|| PdacrtParams::for_device(gpu))),
            date: super::today(),
        }
    }
}

impl Contender {
    /// Its row of the report (median, min and max of the timed frames), with its
    /// tracer's per-level statistics of the last frame where it keeps them (PDACRT).
    fn into_row(
        mut self,
        total_rays: usize,
    ) -> (TracerRow, Option<Vec<crate::trace::pdacrt::LevelStats>>) {
        self.times.sort_by(f64::total_cmp);
        let median = self.times[self.times.len() / 2];
        let tracer = self.tracer.as_deref().expect("created above");
        let stats = tracer.level_stats();
        let (trips, levels) = (
            stats.map(|s| s.host_round_trips),
            stats.map(|s| s.levels.len()),
        );
        let level_stats = stats.map(|s| s.levels.clone());
        let row = TracerRow {
            tracer: self.kind.name().into(),
            frame_ms: median,
            min_ms: self.times[0],
            max_ms: *self.times.last().unwrap(),
            mrays_per_s: total_rays as f64 / (median * 1e3),
            peak_gpu_bytes: self.peak,
            tracer_peak_bytes: self.peak.saturating_sub(self.baseline),
            kernels: self.kernels,
            profile: self.profile,
            subset: 1.0 / self.scale,
            verified_rays: self.verified,
            mismatches: self.mismatches,
            host_round_trips: trips,
            levels,
            host: host_row(&self.host),
        };
        (row, level_stats)
    }
}

/// Medians of a CPU tracer's per-frame host timings (`None` for GPU tracers).
fn host_row(frames: &[HostTiming]) -> Option<HostRow> {
    if frames.is_empty() {
        return None;
    }
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    let trace_ms = median(frames.iter().map(|h| ms(h.trace)), EvenMedian::Upper);
    Some(HostRow {
        build_ms: median(frames.iter().map(|h| ms(h.build)), EvenMedian::Upper),
        trace_ms,
        trace_mrays_per_s: median(
            frames
                .iter()
                .map(|h| h.rays as f64 / (h.trace.as_secs_f64().max(1e-9) * 1e6)),
            EvenMedian::Upper,
        ),
        threads: rayon::current_num_threads(),
    })
}

/// Little-endian records of (u32 triangle index in file order or 0xFFFFFFFF, f32 t), in
/// pixel order, row 0 first.
fn write_hits(path: &Path, hits: &[Hit]) -> BenchResult<()> {
    let mut bytes = Vec::with_capacity(hits.len() * 8);
    for h in hits {
        bytes.extend_from_slice(&h.triangle.to_le_bytes());
        bytes.extend_from_slice(&h.t.to_le_bytes());
    }
    crate::film::atomic::write_bytes_atomically(path, &bytes)?;
    Ok(())
}
