//! The brute-force GPU tracer: every ray against every triangle (glsl/trace/brute_force.comp).

use super::{GpuTriangle, Query, Tracer};
use crate::shaders;
use crate::vk::{self, Buffer, ComputePipeline, Gpu, StreamKind, TimelinePoint};

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct Push {
    ray_count: u32,
    triangle_count: u32,
}

/// Workgroup size and shared-memory batch of the brute-force kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BruteForceTuning {
    pub workgroup_size: u32,
    /// Triangles staged per batch (48 bytes each, within the shared-memory limit).
    pub batch: u32,
}

impl BruteForceTuning {
    /// Large batches on CPU devices (lavapipe), where each workgroup barrier is costly;
    /// moderate ones on GPUs, where occupancy matters more. The batch always fits the
    /// device's shared memory.
    pub fn for_device(gpu: &Gpu) -> Self {
        let limits = &gpu.info().limits;
        let (workgroup_size, batch) = if gpu.info().is_cpu() {
            (64, 512)
        } else {
            (128, 256)
        };
        let max_batch = limits.max_compute_shared_memory_size / 48;
        Self {
            workgroup_size: workgroup_size.min(limits.max_compute_work_group_invocations),
            batch: batch.min(max_batch),
        }
    }
}

pub struct BruteForceTracer {
    gpu: Gpu,
    triangles: Buffer,
    triangle_count: u32,
    closest: ComputePipeline,
    occlusion: ComputePipeline,
}

impl BruteForceTracer {
    pub fn new(gpu: &Gpu, triangles: &[GpuTriangle]) -> vk::Result<Self> {
        Self::with_tuning(gpu, triangles, BruteForceTuning::for_device(gpu))
    }

    pub fn with_tuning(
        gpu: &Gpu,
        triangles: &[GpuTriangle],
        tuning: BruteForceTuning,
    ) -> vk::Result<Self> {
        let pipeline = |kernel| {
            vk::compute_pipeline(
                gpu,
                kernel,
                3,
                size_of::<Push>() as u32,
                &[tuning.workgroup_size, tuning.batch],
            )
        };
        Ok(Self {
            gpu: gpu.clone(),
            triangles: gpu.upload("triangles", triangles)?,
            triangle_count: triangles.len() as u32,
            closest: pipeline(shaders::TRACE_BRUTE_FORCE)?,
            occlusion: pipeline(shaders::TRACE_BRUTE_FORCE__OCCLUSION)?,
        })
    }
}

impl Tracer for BruteForceTracer {
    fn name(&self) -> &'static str {
        "brute-force"
    }

    fn set_geometry(&mut self, triangles: &[GpuTriangle]) -> vk::Result<()> {
        self.gpu.wait_idle()?;
        self.triangles = self.gpu.upload("triangles", triangles)?;
        self.triangle_count = triangles.len() as u32;
        Ok(())
    }

    fn trace(
        &mut self,
        rays: &Buffer,
        hits: &Buffer,
        ray_count: u32,
        query: Query,
        after: &[&TimelinePoint],
    ) -> vk::Result<TimelinePoint> {
        let pipeline = match query {
            Query::ClosestHit => &self.closest,
            Query::Occlusion => &self.occlusion,
        };
        let mut rec = self.gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            pipeline,
            &[(&self.triangles).into(), rays.into(), hits.into()],
            &Push {
                ray_count,
                triangle_count: self.triangle_count,
            },
            ray_count as u64,
        )?;
        rec.submit(after)
    }
}
