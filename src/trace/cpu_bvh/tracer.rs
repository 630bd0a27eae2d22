//! The `cpu-bvh` tracer: a [`CpuBvh`] behind the [`Tracer`] interface. It reads the rays
//! back from their GPU buffer, traces them on every core and writes the hits.

use std::time::Instant;

use super::CpuBvh;
use crate::trace::{GpuTriangle, Hit, HostTiming, Query, Ray, Tracer};
use crate::vk::{self, Buffer, Gpu, StreamKind, TimelinePoint};

pub struct CpuBvhTracer {
    gpu: Gpu,
    bvh: CpuBvh,
    /// Build and traversal times since the last `set_geometry`.
    timing: HostTiming,
}

impl CpuBvhTracer {
    pub fn new(gpu: &Gpu, triangles: &[GpuTriangle]) -> Self {
        let start = Instant::now();
        let span = tracing::info_span!("cpu-bvh build", triangles = triangles.len()).entered();
        let bvh = CpuBvh::new(triangles);
        drop(span);
        Self {
            gpu: gpu.clone(),
            bvh,
            timing: HostTiming {
                build: start.elapsed(),
                ..HostTiming::default()
            },
        }
    }

    pub fn bvh(&self) -> &CpuBvh {
        &self.bvh
    }
}

impl Tracer for CpuBvhTracer {
    fn name(&self) -> &'static str {
        "cpu-bvh"
    }

    fn set_geometry(&mut self, triangles: &[GpuTriangle]) -> vk::Result<()> {
        let start = Instant::now();
        let _span = tracing::info_span!("cpu-bvh build", triangles = triangles.len()).entered();
        self.bvh.rebuild(triangles);
        self.timing = HostTiming {
            build: start.elapsed(),
            ..HostTiming::default()
        };
        Ok(())
    }

    fn host_timing(&self) -> Option<HostTiming> {
        Some(self.timing)
    }

    fn trace(
        &mut self,
        rays: &Buffer,
        hits: &Buffer,
        ray_count: u32,
        query: Query,
        after: &[&TimelinePoint],
    ) -> vk::Result<TimelinePoint> {
        let n = ray_count as usize;
        if rays.element_count::<Ray>() < n || hits.element_count::<Hit>() < n {
            return Err(vk::VkError::Usage(format!(
                "cpu-bvh: {n} rays do not fit buffers '{}' and '{}'",
                rays.name(),
                hits.name()
            )));
        }
        // The rays are written by work the caller orders before `after`.
        for p in after {
            self.gpu.wait(p)?;
        }
        if n > 0 {
            let mut host_rays = rays.read::<Ray>()?;
            host_rays.truncate(n);
            let start = Instant::now();
            let span = tracing::info_span!("cpu-bvh trace", rays = n as u64).entered();
            let host_hits = match query {
                Query::ClosestHit => self.bvh.closest_hits(&host_rays),
                Query::Occlusion => self.bvh.any_hits(&host_rays),
            };
            drop(span);
            self.timing.trace += start.elapsed();
            self.timing.rays += n as u64;
            // `read` drained the main stream and `after` is reached: nothing on the GPU
            // still uses `hits` by the caller's ordering.
            hits.write(&host_hits)?;
        }
        self.gpu.recorder(StreamKind::Main)?.submit(after)
    }
}
