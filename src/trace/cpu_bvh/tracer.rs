//! The `cpu-bvh` tracer: a [`CpuBvh`] behind the [`Tracer`] interface. It reads the rays
//! back from their GPU buffer, traces them on every core and writes the hits.

use std::time::Instant;

use super::CpuBvh;
use crate::trace::{trace_on_host, GpuTriangle, HostTiming, Query, Tracer};
use crate::vk::{self, Buffer, Gpu, TimelinePoint};

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
        let bvh = &self.bvh;
        let (point, traced) = trace_on_host(
            &self.gpu,
            "cpu-bvh",
            (rays, hits),
            ray_count,
            after,
            |host_rays| {
                let _span =
                    tracing::info_span!("cpu-bvh trace", rays = host_rays.len() as u64).entered();
                let hits = match query {
                    Query::ClosestHit => bvh.closest_hits(host_rays),
                    Query::Occlusion => bvh.any_hits(host_rays),
                };
                (hits, ())
            },
        )?;
        if let Some((time, ())) = traced {
            self.timing.trace += time;
            self.timing.rays += ray_count as u64;
        }
        Ok(point)
    }
}
