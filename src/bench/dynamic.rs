//! `splitray bench dynamic`: the comparison PDACRT exists for (paper §1, thesis ch. 2).
//! An animated scene moves frame by frame; each tracer takes the new geometry as a
//! dynamic scene must — PDACRT writes the moved triangles in place and builds nothing,
//! ray-query builds the driver's BLAS and TLAS again (or refits the BLAS, where asked),
//! the CPU DACRT takes the triangles, the CPU BVH builds its tree again — and then
//! traces the frame's primary rays and, from their hits, its shadow rays.
//!
//! One run: after a verified warm-up frame (LLVM compiles each kernel at its first
//! dispatch on lavapipe), every timed frame gives every tracer its turn, in an order
//! that rotates from frame to frame, so that a change of load on a shared machine hits
//! every tracer alike. A frame's time for a workload is the geometry update plus the
//! workload's traces, waited for. Every traced frame is checked against brute force on
//! a sample of its rays (CPU, the same intersection arithmetic) before its time counts.

use std::fmt;
use std::ops::Range;
use std::time::Instant;

use serde::Serialize;

use super::trace::BenchResult;
use super::workloads::{self, Workload};
use super::{median, EvenMedian};
use crate::render::frames::{move_triangles, FrameRange};
use crate::scene::{AnimatedScene, Scene};
use crate::trace::{
    cpu, CpuBvh, CpuBvhTracer, CpuDacrtTracer, GpuTriangle, Hit, PdacrtTracer, Query, Ray,
    RayQueryTracer, Tracer,
};
use crate::vk::{self, Buffer, Gpu};

/// A tracer as a dynamic scene runs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Contender {
    /// Nothing built: the moved triangles are written in place.
    Pdacrt,
    /// The driver's BLAS and TLAS built again every frame.
    RayQuery,
    /// The BLAS refitted (an acceleration-structure update), the TLAS built again.
    RayQueryRefit,
    /// Serial divide and conquer on one CPU thread: takes the triangles.
    CpuDacrt,
    /// The CPU BVH built again every frame, traced on every core.
    CpuBvh,
}

impl Contender {
    pub const ALL: [Contender; 5] = [
        Self::Pdacrt,
        Self::RayQuery,
        Self::RayQueryRefit,
        Self::CpuDacrt,
        Self::CpuBvh,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Self::Pdacrt => "pdacrt",
            Self::RayQuery => "ray-query",
            Self::RayQueryRefit => "ray-query-refit",
            Self::CpuDacrt => "cpu-dacrt",
            Self::CpuBvh => "cpu-bvh",
        }
    }

    fn needs_ray_query(self) -> bool {
        matches!(self, Self::RayQuery | Self::RayQueryRefit)
    }

    fn create(self, gpu: &Gpu, triangles: &[GpuTriangle]) -> vk::Result<Box<dyn Tracer>> {
        Ok(match self {
            Self::Pdacrt => Box::new(PdacrtTracer::new(gpu, triangles)?),
            Self::RayQuery => Box::new(RayQueryTracer::new(gpu, triangles)?),
            Self::RayQueryRefit => Box::new(RayQueryTracer::refitting(gpu, triangles)?),
            Self::CpuDacrt => Box::new(CpuDacrtTracer::new(gpu, triangles)),
            Self::CpuBvh => Box::new(CpuBvhTracer::new(gpu, triangles)),
        })
    }
}

impl std::str::FromStr for Contender {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|c| c.name()).collect();
                format!("unknown tracer '{s}' (choose from: {})", names.join(", "))
            })
    }
}

#[derive(Clone, Debug)]
pub struct DynamicBenchOptions {
    pub width: u32,
    pub height: u32,
    /// The warm-up frame; frames `first + 1 ..= first + frames` are timed.
    pub first: u32,
    /// Timed frames (at least 1).
    pub frames: u32,
    pub fps: f64,
    /// Any workload but `path` (whose bounces need the tracer between batches).
    pub workloads: Vec<Workload>,
    pub contenders: Vec<Contender>,
    /// Rays per batch and frame checked against brute force.
    pub verify_rays: usize,
}

impl Default for DynamicBenchOptions {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            first: 0,
            frames: 8,
            fps: 24.0,
            workloads: vec![Workload::Primary, Workload::Shadow],
            contenders: Contender::ALL.to_vec(),
            verify_rays: 1024,
        }
    }
}

/// One tracer's figures for one workload, medians over the timed frames.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicRow {
    pub tracer: Contender,
    /// Geometry update plus the workload's traces.
    pub frame_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub update_ms: f64,
    pub trace_ms: f64,
    pub mrays_per_s: f64,
    /// Sampled hits checked against brute force, over all frames, and how many differed.
    pub verified_rays: usize,
    pub mismatches: usize,
    /// Every timed frame's time (ms), in frame order.
    pub frames_ms: Vec<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct WorkloadReport {
    pub workload: Workload,
    /// Rays per frame (mean over the timed frames).
    pub rays_per_frame: f64,
    pub rows: Vec<DynamicRow>,
}

#[derive(Clone, Debug, Serialize)]
pub struct DynamicReport {
    pub scene: String,
    pub triangles: usize,
    /// Triangles moved per frame (mean over the timed frames).
    pub moved_triangles: f64,
    pub device: String,
    pub width: u32,
    pub height: u32,
    pub frames: Range<u32>,
    pub fps: f64,
    pub workloads: Vec<WorkloadReport>,
    /// Tracers left out, and why.
    pub skipped: Vec<(Contender, String)>,
    pub date: String,
}

impl DynamicReport {
    /// PDACRT's frame time over ray-query's (rebuilt every frame), per workload: the
    /// target is below 1.
    pub fn pdacrt_over_ray_query(&self) -> Vec<(Workload, f64)> {
        self.workloads
            .iter()
            .filter_map(|w| {
                let ms = |c| w.rows.iter().find(|r| r.tracer == c).map(|r| r.frame_ms);
                Some((
                    w.workload,
                    ms(Contender::Pdacrt)? / ms(Contender::RayQuery)?,
                ))
            })
            .collect()
    }
}

impl fmt::Display for DynamicReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "bench dynamic: {} ({} triangles, {:.0} moved per frame), {}x{}, timed frames \
             {}..{} at {} fps (after warm-up frame {}), on {}",
            self.scene,
            self.triangles,
            self.moved_triangles,
            self.width,
            self.height,
            self.frames.start,
            self.frames.end,
            self.fps,
            self.frames.start - 1,
            self.device
        )?;
        for (c, why) in &self.skipped {
            writeln!(f, "  {} left out: {why}", c.name())?;
        }
        for w in &self.workloads {
            writeln!(
                f,
                "\n{} workload, {:.0} rays per frame:",
                w.workload, w.rays_per_frame
            )?;
            writeln!(
                f,
                "{:<16} {:>10} {:>10} {:>10} {:>10} {:>10} {:>9} {:>11}  pdacrt faster by",
                "tracer",
                "frame ms",
                "min ms",
                "max ms",
                "update ms",
                "trace ms",
                "Mrays/s",
                "verified"
            )?;
            let pdacrt = w.rows.iter().find(|r| r.tracer == Contender::Pdacrt);
            for r in &w.rows {
                writeln!(
                    f,
                    "{:<16} {:>10.2} {:>10.2} {:>10.2} {:>10.2} {:>10.2} {:>9.2} {:>11}  {}",
                    r.tracer.name(),
                    r.frame_ms,
                    r.min_ms,
                    r.max_ms,
                    r.update_ms,
                    r.trace_ms,
                    r.mrays_per_s,
                    format!("{}/{}", r.verified_rays - r.mismatches, r.verified_rays),
                    pdacrt
                        .filter(|p| p.tracer != r.tracer)
                        .map(|p| format!("{:.2}x", r.frame_ms / p.frame_ms))
                        .unwrap_or_default()
                )?;
            }
        }
        let ratios = self.pdacrt_over_ray_query();
        if !ratios.is_empty() {
            let parts: Vec<String> = ratios
                .iter()
                .map(|(w, r)| {
                    let met = if *r < 1.0 { "met" } else { "NOT met" };
                    format!("{w} {r:.4} ({met})")
                })
                .collect();
            writeln!(
                f,
                "\ntarget pdacrt frame time / ray-query (rebuilt every frame) < 1: {}",
                parts.join(", ")
            )?;
        }
        Ok(())
    }
}

/// One workload's ray and hit buffers, written in place every frame as a renderer's
/// are (fresh buffers every frame cost PDACRT a third more time on lavapipe).
struct Slot {
    rays: Buffer,
    hits: Buffer,
}

impl Slot {
    fn new(gpu: &Gpu, capacity: usize) -> vk::Result<Self> {
        Ok(Self {
            rays: gpu.zeroed::<Ray>("dynamic-rays", capacity.max(1))?,
            hits: gpu.zeroed::<Hit>("dynamic-hits", capacity.max(1))?,
        })
    }
}

/// One workload's rays of one frame (in its slot), and the brute-force answers for a
/// strided sample of them.
struct Batch {
    count: u32,
    query: Query,
    sample: Vec<usize>,
    want: Vec<Hit>,
}

impl Batch {
    fn new(
        slot: &Slot,
        rays: &[Ray],
        query: Query,
        triangles: &[GpuTriangle],
        verify: usize,
    ) -> vk::Result<Self> {
        let step = (rays.len() / verify.max(1)).max(1);
        let sample: Vec<usize> = (0..rays.len()).step_by(step).take(verify).collect();
        let sampled: Vec<Ray> = sample.iter().map(|&i| rays[i]).collect();
        let want = match query {
            Query::ClosestHit => cpu::closest_hits(&sampled, triangles),
            Query::Occlusion => {
                use rayon::prelude::*;
                sampled
                    .par_iter()
                    .map(|r| match cpu::occluded(r, triangles) {
                        true => Hit {
                            t: 0.0,
                            triangle: 0,
                            u: 0.0,
                            v: 0.0,
                        },
                        false => Hit::NONE,
                    })
                    .collect()
            }
        };
        slot.rays.write(rays)?;
        Ok(Self {
            count: rays.len() as u32,
            query,
            sample,
            want,
        })
    }

    /// Sampled hits that differ from brute force.
    fn mismatches(&self, slot: &Slot) -> vk::Result<usize> {
        let got = slot.hits.read::<Hit>()?;
        Ok(self
            .sample
            .iter()
            .zip(&self.want)
            .filter(|(&i, w)| match self.query {
                Query::ClosestHit => !cpu::same_hit(&got[i], w, 1e-5, true),
                Query::Occlusion => got[i].is_hit() != w.is_hit(),
            })
            .count())
    }
}

const PATH_REFUSED: &str =
    "bench dynamic takes the workloads of one batch (primary, shadow, reflection, ao), not path";

/// The workloads' batches of the scene as posed: primary rays through the pixel
/// centres and, from their closest hits (the CPU BVH's, verified like every tracer's),
/// the secondary rays (shadow rays to the point light …).
fn frame_batches(
    slots: &[Slot],
    scene: &Scene,
    triangles: &[GpuTriangle],
    opts: &DynamicBenchOptions,
) -> BenchResult<Vec<(Workload, Batch)>> {
    let primary = workloads::primary_rays(scene, opts.width, opts.height);
    let mut out = Vec::new();
    let needs_hits = opts.workloads.iter().any(|w| *w != Workload::Primary);
    let primary_hits = match needs_hits {
        true => CpuBvh::new(triangles).closest_hits(&primary),
        false => Vec::new(),
    };
    for (&w, slot) in opts.workloads.iter().zip(slots) {
        let (rays, query) = match w {
            Workload::Primary => (primary.clone(), Query::ClosestHit),
            Workload::Path => return Err(PATH_REFUSED.into()),
            _ => {
                let mut none = |_: &[Ray]| -> Vec<Hit> { unreachable!("one batch") };
                let batch = workloads::secondary_batches(
                    w,
                    scene,
                    triangles,
                    &primary,
                    &primary_hits,
                    &mut none,
                );
                let b = batch.into_iter().next().expect("one batch");
                (b.rays, b.query)
            }
        };
        out.push((
            w,
            Batch::new(slot, &rays, query, triangles, opts.verify_rays)?,
        ));
    }
    Ok(out)
}

/// One tracer's times per workload and frame.
struct Timed {
    contender: Contender,
    tracer: Box<dyn Tracer>,
    /// Per workload: (update ms, trace ms, rays) per timed frame.
    frames: Vec<Vec<(f64, f64, u32)>>,
    verified: usize,
    mismatches: usize,
}

/// Moves `tracer` to the frame (`changed`), then traces every batch in turn; returns the
/// update time and each batch's trace time in ms. Verifies every batch.
fn run_frame(
    gpu: &Gpu,
    timed: &mut Timed,
    triangles: &[GpuTriangle],
    changed: Option<&[Range<usize>]>,
    (slots, batches): (&[Slot], &[(Workload, Batch)]),
    frame: u32,
) -> BenchResult<(f64, Vec<f64>)> {
    gpu.wait_idle()?;
    let start = Instant::now();
    if let Some(changed) = changed {
        timed.tracer.update_geometry(triangles, changed)?;
    }
    let update_ms = start.elapsed().as_secs_f64() * 1e3;
    let mut trace_ms = Vec::with_capacity(batches.len());
    for (slot, (w, b)) in slots.iter().zip(batches) {
        gpu.wait_idle()?;
        let start = Instant::now();
        let done = timed
            .tracer
            .trace(&slot.rays, &slot.hits, b.count, b.query, &[])?;
        gpu.wait(&done)?;
        trace_ms.push(start.elapsed().as_secs_f64() * 1e3);
        let wrong = b.mismatches(slot)?;
        timed.verified += b.sample.len();
        timed.mismatches += wrong;
        if wrong > 0 {
            return Err(format!(
                "{}: {wrong} of {} sampled {w} hits of frame {frame} differ from brute force; \
                 not timing it",
                timed.contender.name(),
                b.sample.len()
            )
            .into());
        }
    }
    Ok((update_ms, trace_ms))
}

/// Runs the benchmark on `animated` (which must move).
pub fn run(
    gpu: &Gpu,
    animated: &AnimatedScene,
    opts: &DynamicBenchOptions,
) -> BenchResult<DynamicReport> {
    check_options(animated, opts)?;
    let range = FrameRange {
        first: opts.first,
        end: opts.first + opts.frames + 1,
        fps: opts.fps,
    };
    let mut t = range.time(range.first);
    let mut scene = animated.pose(t);
    let mut triangles = scene.gpu_triangles();
    let (mut contenders, skipped) = create_contenders(gpu, opts, &triangles)?;
    let slots = workload_slots(gpu, opts)?;
    // Warm-up: the first frame as the tracers were built for it, verified, not timed.
    let batches = frame_batches(&slots, &scene, &triangles, opts)?;
    for c in &mut contenders {
        run_frame(gpu, c, &triangles, None, (&slots, &batches), range.first)?;
    }

    let mut moved = 0usize;
    let mut rays = vec![0usize; opts.workloads.len()];
    for (n, k) in (range.first + 1..range.end).enumerate() {
        let next = range.time(k);
        let changed = animated.advance(&mut scene, t, next);
        t = next;
        moved += move_triangles(&mut triangles, &scene, &changed);
        gpu.wait_idle()?;
        let batches = frame_batches(&slots, &scene, &triangles, opts)?;
        for (i, (_, b)) in batches.iter().enumerate() {
            rays[i] += b.count as usize;
        }
        run_frame_in_turn(
            gpu,
            &mut contenders,
            &triangles,
            &changed,
            (&slots, &batches),
            n,
            k,
        )?;
        crate::err!(".");
    }
    crate::errln!();

    let frames = opts.frames as f64;
    Ok(DynamicReport {
        scene: animated.scene.name.clone(),
        triangles: triangles.len(),
        moved_triangles: moved as f64 / frames,
        device: crate::render::device_description(gpu),
        width: opts.width,
        height: opts.height,
        frames: range.first + 1..range.end,
        fps: opts.fps,
        workloads: workload_reports(opts, &contenders, &rays),
        skipped,
        date: super::today(),
    })
}

/// Refuses a scene that does not move, no timed frame, a frame rate that is not a positive
/// number and the path workload.
fn check_options(animated: &AnimatedScene, opts: &DynamicBenchOptions) -> BenchResult<()> {
    if !animated.is_animated() {
        return Err(format!(
            "scene '{}' does not move: bench dynamic needs an animated scene (waves, swarm, \
             or a scene file with keyframes or an OBJ sequence)",
            animated.scene.name
        )
        .into());
    }
    if opts.frames == 0 {
        return Err("bench dynamic needs at least one timed frame".into());
    }
    // The warm-up frame, then the timed ones: all numbered within u32.
    if opts
        .first
        .checked_add(opts.frames)
        .and_then(|e| e.checked_add(1))
        .is_none()
    {
        return Err(format!(
            "--first {} --frames {}: frames past {} cannot be numbered",
            opts.first,
            opts.frames,
            u32::MAX
        )
        .into());
    }
    if !(opts.fps.is_finite() && opts.fps > 0.0) {
        return Err(format!("--fps {} must be a positive number", opts.fps).into());
    }
    if opts.workloads.contains(&Workload::Path) {
        return Err(PATH_REFUSED.into());
    }
    Ok(())
}

/// Tracers left out, and why.
type Skipped = Vec<(Contender, String)>;

/// The tracers of `opts` built on `triangles`, and those the device cannot run.
fn create_contenders(
    gpu: &Gpu,
    opts: &DynamicBenchOptions,
    triangles: &[GpuTriangle],
) -> vk::Result<(Vec<Timed>, Skipped)> {
    let mut skipped = Vec::new();
    let mut contenders = Vec::new();
    for &c in &opts.contenders {
        if c.needs_ray_query() && !gpu.ray_query() {
            skipped.push((
                c,
                crate::trace::ray_query::unsupported_reason(gpu).unwrap_or_default(),
            ));
            continue;
        }
        contenders.push(Timed {
            contender: c,
            tracer: c.create(gpu, triangles)?,
            frames: vec![Vec::new(); opts.workloads.len()],
            verified: 0,
            mismatches: 0,
        });
    }
    Ok((contenders, skipped))
}

/// One slot per workload, large enough for its rays.
fn workload_slots(gpu: &Gpu, opts: &DynamicBenchOptions) -> vk::Result<Vec<Slot>> {
    // Secondary rays start at primary hits: at most one per pixel (AO: several).
    let pixels = opts.width as usize * opts.height as usize;
    opts.workloads
        .iter()
        .map(|w| match w {
            Workload::Ao => Slot::new(gpu, pixels * workloads::AO_RAYS),
            _ => Slot::new(gpu, pixels),
        })
        .collect()
}

/// Timed frame `frame`, the `n`th: every tracer in turn, starting with the `n`th (mod
/// their number) so that the order rotates from frame to frame; records their times.
fn run_frame_in_turn(
    gpu: &Gpu,
    contenders: &mut [Timed],
    triangles: &[GpuTriangle],
    changed: &[Range<usize>],
    (slots, batches): (&[Slot], &[(Workload, Batch)]),
    n: usize,
    frame: u32,
) -> BenchResult<()> {
    let count = contenders.len();
    for i in 0..count {
        let c = &mut contenders[(i + n) % count];
        let (update, traces) =
            run_frame(gpu, c, triangles, Some(changed), (slots, batches), frame)?;
        for (w, (ms, (_, b))) in traces.iter().zip(batches).enumerate() {
            c.frames[w].push((update, *ms, b.count));
        }
    }
    Ok(())
}

/// Per workload: its rays per frame (`rays` summed over the timed frames) and every
/// tracer's row.
fn workload_reports(
    opts: &DynamicBenchOptions,
    contenders: &[Timed],
    rays: &[usize],
) -> Vec<WorkloadReport> {
    let frames = opts.frames as f64;
    opts.workloads
        .iter()
        .enumerate()
        .map(|(w, &workload)| WorkloadReport {
            workload,
            rays_per_frame: rays[w] as f64 / frames,
            rows: contenders.iter().map(|c| row(c, &c.frames[w])).collect(),
        })
        .collect()
}

fn row(c: &Timed, frames: &[(f64, f64, u32)]) -> DynamicRow {
    let totals: Vec<f64> = frames.iter().map(|(u, t, _)| u + t).collect();
    let rates: Vec<f64> = frames
        .iter()
        .map(|(u, t, n)| *n as f64 / ((u + t) * 1e3))
        .collect();
    DynamicRow {
        tracer: c.contender,
        frame_ms: median(totals.iter().copied(), EvenMedian::Upper),
        min_ms: totals.iter().copied().fold(f64::INFINITY, f64::min),
        max_ms: totals.iter().copied().fold(0.0, f64::max),
        update_ms: median(frames.iter().map(|f| f.0), EvenMedian::Upper),
        trace_ms: median(frames.iter().map(|f| f.1), EvenMedian::Upper),
        mrays_per_s: median(rates, EvenMedian::Upper),
        verified_rays: c.verified,
        mismatches: c.mismatches,
        frames_ms: totals,
    }
}
