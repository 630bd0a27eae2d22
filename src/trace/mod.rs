//! Tracers: closest-hit and occlusion queries for batches of rays.
//!
//! Every integrator goes through the [`Tracer`] interface, so tracers are interchangeable
//! (`--tracer NAME`). Rays and hits live in GPU buffers; a tracer may submit as much work
//! as it needs (PDACRT runs host-driven level loops) and returns the timeline point that
//! marks its hits as written.

pub mod brute_force;
pub mod cpu;
pub mod cpu_bvh;
pub mod cpu_dacrt;
pub mod pdacrt;
pub mod ray_query;
pub mod types;

use std::fmt;
use std::str::FromStr;

pub use brute_force::BruteForceTracer;
pub use cpu_bvh::{CpuBvh, CpuBvhTracer};
pub use cpu_dacrt::{CpuDacrtTracer, DacrtParams};
pub use pdacrt::{FlushReduce, LevelSplit, PdacrtParams, PdacrtTracer};
pub use ray_query::RayQueryTracer;
pub use types::{GpuTriangle, Hit, Ray, MISS};

use crate::vk::{self, Buffer, Gpu, TimelinePoint};

/// What a query asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// The nearest hit within (tmin, tmax).
    ClosestHit,
    /// Any hit within (tmin, tmax): shadow and ambient-occlusion rays.
    Occlusion,
}

/// Casts batches of rays against one scene's triangles. A ray whose segment is empty
/// (tmax <= tmin, NaN included) hits nothing: the integrators write such rays (tmax = 0)
/// into slots that have no ray, and a tracer should spend no traversal on them (PDACRT
/// drops them at its root).
pub trait Tracer {
    fn name(&self) -> &'static str;

    /// Replaces the triangles, as a dynamic scene does every frame: whatever the tracer
    /// builds from them (an acceleration structure, or nothing at all for PDACRT) is
    /// built again. Returns once the new geometry is in place.
    fn set_geometry(&mut self, triangles: &[GpuTriangle]) -> vk::Result<()>;

    /// The next frame of a dynamic scene: `triangles` is the whole new soup (of the same
    /// length as before), of which only the ranges `changed` differ from the last
    /// geometry. Tracers that keep the triangles as they are update those ranges in
    /// place; the others build again, as [`Tracer::set_geometry`] does.
    fn update_geometry(
        &mut self,
        triangles: &[GpuTriangle],
        changed: &[std::ops::Range<usize>],
    ) -> vk::Result<()> {
        let _ = changed;
        self.set_geometry(triangles)
    }

    /// Traces `ray_count` rays from `rays` into `hits` (one [`Hit`] per ray). The work
    /// starts after every point in `after` and the returned point marks it done; the
    /// tracer and the buffers must outlive that point.
    fn trace(
        &mut self,
        rays: &Buffer,
        hits: &Buffer,
        ray_count: u32,
        query: Query,
        after: &[&TimelinePoint],
    ) -> vk::Result<TimelinePoint>;

    /// Per-level statistics of the last trace, for tracers that work in levels (PDACRT).
    fn level_stats(&self) -> Option<&pdacrt::TraceStats> {
        None
    }

    /// Host time of the geometry build and of the traversals since the last
    /// `set_geometry`, for tracers that trace on the CPU (GPU buffer transfers excluded).
    fn host_timing(&self) -> Option<HostTiming> {
        None
    }
}

/// What a CPU tracer spent on the host since its last `set_geometry`.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct HostTiming {
    /// Building the acceleration structure (zero for tracers that build nothing).
    pub build: std::time::Duration,
    /// The traversals alone: rays read back and hits written are not included.
    pub trace: std::time::Duration,
    /// Rays traced in that time.
    pub rays: u64,
}

/// The tracers a user can pick.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TracerKind {
    #[default]
    Pdacrt,
    BruteForce,
    CpuDacrt,
    CpuBvh,
    RayQuery,
}

impl TracerKind {
    pub const ALL: &'static [(TracerKind, &'static str)] = &[
        (
            TracerKind::Pdacrt,
            "parallel divide-and-conquer ray tracing: no acceleration structure, level loops on the GPU",
        ),
        (
            TracerKind::BruteForce,
            "every ray against every triangle on the GPU: the correctness oracle",
        ),
        (
            TracerKind::CpuDacrt,
            "serial divide-and-conquer ray tracing on one CPU thread (Mora 2011): the baseline",
        ),
        (
            TracerKind::CpuBvh,
            "a BVH (obvhs: PLOC + 8-wide CWBVH) built and traced on every CPU core; rays and hits pass through host memory",
        ),
        (
            TracerKind::RayQuery,
            "the driver's BLAS/TLAS traced with VK_KHR_ray_query (where the device offers it)",
        ),
    ];

    pub fn name(self) -> &'static str {
        match self {
            Self::Pdacrt => "pdacrt",
            Self::BruteForce => "brute-force",
            Self::CpuDacrt => "cpu-dacrt",
            Self::CpuBvh => "cpu-bvh",
            Self::RayQuery => "ray-query",
        }
    }

    /// Builds the tracer over `triangles`.
    pub fn create(self, gpu: &Gpu, triangles: &[GpuTriangle]) -> vk::Result<Box<dyn Tracer>> {
        match self {
            Self::Pdacrt => Ok(Box::new(PdacrtTracer::new(gpu, triangles)?)),
            Self::BruteForce => Ok(Box::new(BruteForceTracer::new(gpu, triangles)?)),
            Self::CpuDacrt => Ok(Box::new(CpuDacrtTracer::new(gpu, triangles))),
            Self::CpuBvh => Ok(Box::new(CpuBvhTracer::new(gpu, triangles))),
            Self::RayQuery => Ok(Box::new(RayQueryTracer::new(gpu, triangles)?)),
        }
    }
}

impl fmt::Display for TracerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for TracerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .iter()
            .find(|(k, _)| k.name() == s)
            .map(|(k, _)| *k)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|(k, _)| k.name()).collect();
                format!("unknown tracer '{s}' (choose one of: {})", names.join(", "))
            })
    }
}

/// The part every tracer that runs on the host shares: check that `ray_count` rays fit
/// both buffers, wait for `after` (the work that wrote the rays), read the rays, run
/// `trace` on them (timed: the duration comes back with what `trace` returns) and write
/// its hits; the returned point is on the main stream after `after`. No rays, no trace.
pub(crate) fn trace_on_host<S>(
    gpu: &Gpu,
    tracer: &str,
    (rays, hits): (&Buffer, &Buffer),
    ray_count: u32,
    after: &[&TimelinePoint],
    trace: impl FnOnce(&[Ray]) -> (Vec<Hit>, S),
) -> vk::Result<(TimelinePoint, Option<(std::time::Duration, S)>)> {
    let n = ray_count as usize;
    if rays.element_count::<Ray>() < n || hits.element_count::<Hit>() < n {
        return Err(vk::VkError::Usage(format!(
            "{tracer}: {n} rays do not fit buffers '{}' and '{}'",
            rays.name(),
            hits.name()
        )));
    }
    // The rays are written by work the caller orders before `after`.
    for p in after {
        gpu.wait(p)?;
    }
    let mut traced = None;
    if n > 0 {
        let mut host_rays = rays.read::<Ray>()?;
        host_rays.truncate(n);
        let start = std::time::Instant::now();
        let (host_hits, extra) = trace(&host_rays);
        traced = Some((start.elapsed(), extra));
        // `read` drained the main stream and `after` is reached: nothing on the GPU
        // still uses `hits` by the caller's ordering.
        hits.write(&host_hits)?;
    }
    let point = gpu.recorder(vk::StreamKind::Main)?.submit(after)?;
    Ok((point, traced))
}
