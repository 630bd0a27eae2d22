//! `splitray bench trace`: build + trace time per frame for each tracer on one scene and
//! workload, with Mrays/s, peak GPU memory and ratios between tracers, all measured in
//! the same run. Every tracer's hits are checked against brute force on a sample of
//! rays before anything is timed.

use std::fmt;
use std::io::Write as _;
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

impl fmt::Display for TraceReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
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
        )?;
        for r in &self.rows {
            let ratios: Vec<String> = self
                .rows
                .iter()
                .filter(|o| o.tracer != r.tracer)
                .map(|o| format!("{:.2}x {}", o.frame_ms / r.frame_ms, o.tracer))
                .collect();
            writeln!(
                f,
                "{:<12} {:>11.2} {:>10.2} {:>10.2} {:>10.2} {:>11.1} {:>11.1} {:>9}  faster than: {}{}",
                r.tracer,
                r.frame_ms,
                r.min_ms,
                r.max_ms,
                r.mrays_per_s,
                r.peak_gpu_bytes as f64 / (1 << 20) as f64,
                r.tracer_peak_bytes as f64 / (1 << 20) as f64,
                format!("{}/{}", r.verified_rays - r.mismatches, r.verified_rays),
                ratios.join(", "),
                if r.subset < 1.0 {
                    format!("  [extrapolated from {:.2}% of the rays]", 100.0 * r.subset)
                } else {
                    String::new()
                }
            )?;
            if let Some(h) = &r.host {
                writeln!(
                    f,
                    "{:<12} on the host: build {:.2} ms, trace {:.2} ms = {:.2} Mrays/s on {} threads (frame less build and trace: {:.2} ms of ray and hit transfers)",
                    "",
                    h.build_ms,
                    h.trace_ms,
                    h.trace_mrays_per_s,
                    h.threads,
                    (r.frame_ms - h.build_ms - h.trace_ms).max(0.0)
                )?;
            }
            if let (Some(trips), Some(levels)) = (r.host_round_trips, r.levels) {
                writeln!(
                    f,
                    "{:<12} {levels} levels, {trips} host round trips per frame",
                    ""
                )?;
            }
            if let (true, Some(p)) = (r.tracer == "pdacrt", &self.pdacrt_params) {
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
                )?;
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
                )?;
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

/// Runs the benchmark. `dump_hits`: write the primary hits (pixel order) there.
pub fn run(
    gpu: &Gpu,
    scene: &Scene,
    opts: &TraceBenchOptions,
    dump_hits: Option<&Path>,
) -> BenchResult<TraceReport> {
    let triangles: Vec<GpuTriangle> = scene
        .triangles
        .iter()
        .map(|t| GpuTriangle::new(t.p))
        .collect();
    let primary = workloads::primary_rays(scene, opts.width, opts.height);

    // The workload's rays, from PDACRT's primary hits (checked below like every tracer).
    let mut reference = PdacrtTracer::new(gpu, &triangles)?;
    let primary_hits = trace_once(gpu, &mut reference, &primary, Query::ClosestHit)?;
    if let Some(path) = dump_hits {
        write_hits(path, &primary_hits)?;
    }
    let mut batches: Vec<RayBatch> = Vec::new();
    if opts.workload == Workload::Primary {
        batches.push(RayBatch {
            label: "primary".into(),
            rays: primary.clone(),
            query: Query::ClosestHit,
        });
    } else {
        let mut trace = |rays: &[Ray]| {
            trace_once(gpu, &mut reference, rays, Query::ClosestHit).expect("trace bounce")
        };
        batches = workloads::secondary_batches(
            opts.workload,
            scene,
            &triangles,
            &primary,
            &primary_hits,
            &mut trace,
        );
    }
    drop(reference);
    let total_rays: usize = batches.iter().map(|b| b.rays.len()).sum();

    let gpu_batches: Vec<GpuBatch> = batches
        .iter()
        .map(|b| -> vk::Result<GpuBatch> {
            Ok(GpuBatch {
                rays: gpu.upload("bench-rays", &b.rays)?,
                hits: gpu.create_buffer(
                    "bench-hits",
                    (b.rays.len().max(1) * size_of::<Hit>()) as u64,
                    vk::MemoryKind::Device,
                )?,
                count: b.rays.len() as u32,
                query: b.query,
            })
        })
        .collect::<vk::Result<_>>()?;

    // Brute-force samples for verification (the oracle of every tracer).
    let mut oracle = BruteForceTracer::new(gpu, &triangles)?;
    let affordable = (opts.verify_budget / triangles.len().max(1) as f64) as usize;
    let verify_rays = affordable.clamp(64.min(opts.verify_rays), opts.verify_rays);
    let samples: Vec<(Vec<Ray>, Vec<Hit>, Query)> = batches
        .iter()
        .map(|b| -> vk::Result<_> {
            let rays = strided(&b.rays, verify_rays);
            let hits = trace_once(gpu, &mut oracle, &rays, b.query)?;
            Ok((rays, hits, b.query))
        })
        .collect::<vk::Result<_>>()?;
    drop(oracle);

    // Phase 1, per tracer alone on the device: verify it, then measure its peak memory
    // over a warm-up frame and one more (its pools persist between frames, so another
    // tracer alive at the same time would blur both figures).
    let make = |kind: TracerKind| -> vk::Result<Box<dyn Tracer>> {
        match (kind, opts.pdacrt) {
            (TracerKind::Pdacrt, Some(params)) => Ok(Box::new(PdacrtTracer::with_params(
                gpu, &triangles, params,
            )?)),
            _ => kind.create(gpu, &triangles),
        }
    };
    let mut contenders = Vec::new();
    for &kind in &opts.tracers {
        let mut tracer = make(kind)?;
        // Verify before timing.
        let (mut verified, mut mismatches) = (0, 0);
        for (rays, want, query) in &samples {
            let got = trace_once(gpu, tracer.as_mut(), rays, *query)?;
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
        if mismatches > 0 {
            return Err(format!("{}: {mismatches} of {verified} sampled hits differ from brute force; not timing it", kind.name()).into());
        }
        // Brute force on a subset when the whole frame would take too long.
        let tests = triangles.len() as f64 * total_rays as f64;
        let subset = if kind == TracerKind::BruteForce && tests > opts.brute_force_budget {
            opts.brute_force_budget / tests
        } else {
            1.0
        };
        let subset_batches = if subset < 1.0 {
            Some(
                batches
                    .iter()
                    .map(|b| -> vk::Result<GpuBatch> {
                        let rays = strided(
                            &b.rays,
                            ((b.rays.len() as f64 * subset).ceil() as usize).max(1),
                        );
                        Ok(GpuBatch {
                            rays: gpu.upload("bench-rays", &rays)?,
                            hits: gpu.create_buffer(
                                "bench-hits",
                                (rays.len() * size_of::<Hit>()) as u64,
                                vk::MemoryKind::Device,
                            )?,
                            count: rays.len() as u32,
                            query: b.query,
                        })
                    })
                    .collect::<vk::Result<Vec<_>>>()?,
            )
        } else {
            None
        };
        let timed = subset_batches.as_deref().unwrap_or(&gpu_batches);
        let traced: usize = timed.iter().map(|b| b.count as usize).sum();
        let scale = total_rays as f64 / traced.max(1) as f64;

        // Everything on the device before the tracer's first frame: rays, hits and the
        // bench's own buffers (the tracer's pipelines hold no device memory).
        drop(tracer);
        gpu.wait_idle()?;
        let baseline = gpu.memory_bytes().0;
        let mut tracer = make(kind)?;
        let mut peak = 0;
        for _ in 0..2 {
            gpu.wait_idle()?;
            gpu.reset_peak_memory();
            run_frame(gpu, tracer.as_mut(), &triangles, timed)?;
            peak = peak.max(gpu.memory_bytes().1);
        }
        drop(tracer);
        gpu.wait_idle()?;
        let _ = gpu.take_profile();
        contenders.push(Contender {
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
        });
    }

    // Phase 2: all tracers together, one warm-up frame each (LLVM compiles each kernel
    // at its first dispatch on lavapipe), then timed frames in interleaved rounds, so
    // that a change of load on a shared machine hits every tracer alike.
    for c in &mut contenders {
        let mut tracer = make(c.kind)?;
        let timed = c.subset_batches.as_deref().unwrap_or(&gpu_batches);
        run_frame(gpu, tracer.as_mut(), &triangles, timed)?;
        c.tracer = Some(tracer);
    }
    let _ = gpu.take_profile();
    for _ in 0..opts.frames.max(5) {
        for c in &mut contenders {
            let timed = c.subset_batches.as_deref().unwrap_or(&gpu_batches);
            let tracer = c.tracer.as_deref_mut().expect("created above");
            let ms = run_frame(gpu, tracer, &triangles, timed)?;
            c.times.push(ms * c.scale);
            c.host.extend(tracer.host_timing());
            let log = gpu.take_profile();
            c.kernels = log.summary();
            c.profile = log.tree();
        }
        eprint!(".");
        let _ = std::io::stderr().flush();
    }
    eprintln!();

    let mut rows = Vec::new();
    let mut pdacrt_levels = Vec::new();
    for mut c in contenders {
        c.times.sort_by(f64::total_cmp);
        let median = c.times[c.times.len() / 2];
        let tracer = c.tracer.as_deref().expect("created above");
        let stats = tracer.level_stats();
        let (trips, levels) = (
            stats.map(|s| s.host_round_trips),
            stats.map(|s| s.levels.len()),
        );
        if let Some(stats) = stats {
            pdacrt_levels = stats.levels.clone();
        }
        rows.push(TracerRow {
            tracer: c.kind.name().into(),
            frame_ms: median,
            min_ms: c.times[0],
            max_ms: *c.times.last().unwrap(),
            mrays_per_s: total_rays as f64 / (median * 1e3),
            peak_gpu_bytes: c.peak,
            tracer_peak_bytes: c.peak.saturating_sub(c.baseline),
            kernels: c.kernels,
            profile: c.profile,
            subset: 1.0 / c.scale,
            verified_rays: c.verified,
            mismatches: c.mismatches,
            host_round_trips: trips,
            levels,
            host: host_row(&c.host),
        });
    }
    Ok(TraceReport {
        scene: scene.name.clone(),
        triangles: triangles.len(),
        device: crate::render::device_description(gpu),
        width: opts.width,
        height: opts.height,
        workload: opts.workload,
        batches: batches
            .iter()
            .map(|b| (b.label.clone(), b.rays.len()))
            .collect(),
        rays: total_rays,
        rows,
        pdacrt_levels,
        pdacrt_params: opts
            .tracers
            .contains(&TracerKind::Pdacrt)
            .then(|| opts.pdacrt.unwrap_or_else(|| PdacrtParams::for_device(gpu))),
        date: super::today(),
    })
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
