//! The ray-query tracer: the driver's own acceleration structure (one BLAS over the
//! triangles, one TLAS instance of it) traced with `rayQueryEXT` in a compute kernel
//! (glsl/trace/ray_query.comp). Available where the device offers VK_KHR_ray_query and
//! VK_KHR_acceleration_structure; it is the hardware/driver reference the DACRT tracers
//! are compared with.
//!
//! The structures are built when the tracer is created and on every [`RayQueryTracer::
//! rebuild`] (dynamic scenes rebuild every frame), so the build time is part of the
//! cost and is reported by [`RayQueryTracer::build_time`] (and in the GPU profile under
//! `build-blas:…` / `build-tlas:…`). A [`RayQueryTracer::refitting`] tracer refits its
//! BLAS instead when a frame moves the triangles (`update-blas:…`). Ties in t are broken by the driver, not by the
//! smaller triangle index; hit distances agree with brute force to rounding.

use std::time::{Duration, Instant};

use super::{GpuTriangle, Hit, Query, Tracer};
use crate::shaders;
use crate::vk::{
    self, AccelerationStructure, Buffer, BufferUsage, ComputePipeline, Gpu, MemoryKind,
    PipelineDesc, StreamKind, TimelinePoint, VkError,
};

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct Push {
    ray_count: u32,
}

/// The built scene. Field order is drop order: the TLAS before the BLAS it references,
/// the BLAS before its vertices.
struct Scene {
    tlas: AccelerationStructure,
    blas: AccelerationStructure,
    vertices: Buffer,
    triangle_count: usize,
}

pub struct RayQueryTracer {
    gpu: Gpu,
    closest: ComputePipeline,
    occlusion: ComputePipeline,
    /// `None` for an empty scene: every ray misses.
    scene: Option<Scene>,
    /// Dynamic scenes refit the BLAS (an update of the one built first) instead of
    /// building it again.
    refit: bool,
    build_time: Duration,
    /// The last submission that reads the scene, waited for before it is replaced.
    last_use: Option<TimelinePoint>,
}

/// Why the device cannot run this tracer, or `None` when it can.
pub fn unsupported_reason(gpu: &Gpu) -> Option<String> {
    (!gpu.ray_query()).then(|| {
        format!(
            "the ray-query tracer needs VK_KHR_ray_query (with VK_KHR_acceleration_structure, \
             VK_KHR_deferred_host_operations and the rayQuery, accelerationStructure and \
             bufferDeviceAddress features), which device '{}' does not offer",
            gpu.info().name
        )
    })
}

/// Non-indexed vertex positions of the triangles, 9 f32 each.
fn vertices_of(triangles: &[GpuTriangle]) -> Vec<f32> {
    let mut out = Vec::with_capacity(triangles.len() * 9);
    for t in triangles {
        for p in t.vertices() {
            out.extend(<[f32; 3]>::from(p));
        }
    }
    out
}

impl RayQueryTracer {
    pub fn new(gpu: &Gpu, triangles: &[GpuTriangle]) -> vk::Result<Self> {
        Self::with_refit(gpu, triangles, false)
    }

    /// A tracer whose [`Tracer::update_geometry`] refits the BLAS built at creation (an
    /// acceleration-structure update, where every device that has the extension allows
    /// one) and builds the TLAS again, instead of building both again.
    pub fn refitting(gpu: &Gpu, triangles: &[GpuTriangle]) -> vk::Result<Self> {
        Self::with_refit(gpu, triangles, true)
    }

    fn with_refit(gpu: &Gpu, triangles: &[GpuTriangle], refit: bool) -> vk::Result<Self> {
        if let Some(reason) = unsupported_reason(gpu) {
            return Err(VkError::Usage(reason));
        }
        let pipeline = |kernel| {
            ComputePipeline::with_acceleration_structure(
                gpu,
                &PipelineDesc {
                    kernel,
                    bindings: 2,
                    push_constant_bytes: size_of::<Push>() as u32,
                    spec: &[64u32.min(gpu.info().limits.max_compute_work_group_invocations)],
                },
            )
        };
        let mut tracer = Self {
            gpu: gpu.clone(),
            closest: pipeline(shaders::TRACE_RAY_QUERY)?,
            occlusion: pipeline(shaders::TRACE_RAY_QUERY__OCCLUSION)?,
            scene: None,
            refit,
            build_time: Duration::ZERO,
            last_use: None,
        };
        tracer.rebuild(triangles)?;
        Ok(tracer)
    }

    /// Rebuilds the BLAS and TLAS over `triangles` (a new frame of a dynamic scene) and
    /// returns the build time: vertex upload, both builds, and the wait for them.
    pub fn rebuild(&mut self, triangles: &[GpuTriangle]) -> vk::Result<Duration> {
        if let Some(p) = self.last_use.take() {
            self.gpu.wait(&p)?;
        }
        self.scene = None;
        let start = Instant::now();
        if !triangles.is_empty() {
            let positions = vertices_of(triangles);
            let vertices = self.gpu.create_buffer_with(
                "ray-query:vertices",
                (positions.len() * size_of::<f32>()) as u64,
                MemoryKind::Device,
                BufferUsage::ACCEL_BUILD_INPUT,
            )?;
            vertices.write(&positions)?;
            let mut rec = self.gpu.recorder(StreamKind::Main)?;
            let build = match self.refit {
                true => AccelerationStructure::build_triangles_updatable,
                false => AccelerationStructure::build_triangles,
            };
            let blas = build(
                &mut rec,
                "ray-query:blas",
                &vertices,
                triangles.len() as u32,
            )?;
            let tlas =
                AccelerationStructure::build_single_instance(&mut rec, "ray-query:tlas", &blas)?;
            let done = rec.submit(&[])?;
            self.gpu.wait(&done)?;
            self.scene = Some(Scene {
                tlas,
                blas,
                vertices,
                triangle_count: triangles.len(),
            });
        }
        self.build_time = start.elapsed();
        Ok(self.build_time)
    }

    /// Moves the triangles in `changed` to where `triangles` has them, refitting the
    /// BLAS in place, and builds the TLAS again; returns the time taken (vertex upload,
    /// update, TLAS build and the wait for them).
    fn refit_geometry(
        &mut self,
        triangles: &[GpuTriangle],
        changed: &[std::ops::Range<usize>],
    ) -> vk::Result<Duration> {
        if let Some(p) = self.last_use.take() {
            self.gpu.wait(&p)?;
        }
        let start = Instant::now();
        let scene = self.scene.as_mut().expect("checked by the caller");
        for range in changed {
            scene
                .vertices
                .write_at(range.start * 9, &vertices_of(&triangles[range.clone()]))?;
        }
        let mut rec = self.gpu.recorder(StreamKind::Main)?;
        scene.blas.update_triangles(&mut rec, &scene.vertices)?;
        let tlas =
            AccelerationStructure::build_single_instance(&mut rec, "ray-query:tlas", &scene.blas)?;
        let done = rec.submit(&[])?;
        self.gpu.wait(&done)?;
        scene.tlas = tlas;
        self.build_time = start.elapsed();
        Ok(self.build_time)
    }

    /// Host wall time of the last build (creation or [`Self::rebuild`]).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Bytes of the BLAS and TLAS storage.
    pub fn acceleration_structure_bytes(&self) -> u64 {
        self.scene
            .as_ref()
            .map_or(0, |s| s.blas.size() + s.tlas.size())
    }
}

impl Tracer for RayQueryTracer {
    fn name(&self) -> &'static str {
        "ray-query"
    }

    /// A full BLAS + TLAS build, as a dynamic scene needs every frame.
    fn set_geometry(&mut self, triangles: &[GpuTriangle]) -> vk::Result<()> {
        self.rebuild(triangles).map(|_| ())
    }

    /// A refit where the tracer was made [`RayQueryTracer::refitting`] and the triangle
    /// count is the same, else a full build.
    fn update_geometry(
        &mut self,
        triangles: &[GpuTriangle],
        changed: &[std::ops::Range<usize>],
    ) -> vk::Result<()> {
        let same_count = self
            .scene
            .as_ref()
            .is_some_and(|s| s.triangle_count == triangles.len());
        let in_range = changed
            .iter()
            .all(|r| r.start <= r.end && r.end <= triangles.len());
        if self.refit && same_count && in_range {
            self.refit_geometry(triangles, changed).map(|_| ())
        } else {
            self.rebuild(triangles).map(|_| ())
        }
    }

    fn trace(
        &mut self,
        rays: &Buffer,
        hits: &Buffer,
        ray_count: u32,
        query: Query,
        after: &[&TimelinePoint],
    ) -> vk::Result<TimelinePoint> {
        let mut rec = self.gpu.recorder(StreamKind::Main)?;
        match &self.scene {
            Some(scene) => {
                let pipeline = match query {
                    Query::ClosestHit => &self.closest,
                    Query::Occlusion => &self.occlusion,
                };
                rec.dispatch_with_tlas(
                    pipeline,
                    &[rays.into(), hits.into()],
                    &scene.tlas,
                    &Push { ray_count },
                    ray_count as u64,
                )?;
            }
            None => {
                // No triangles: every ray misses.
                for p in after {
                    self.gpu.wait(p)?;
                }
                self.gpu.wait(&rec.submit(&[])?)?;
                hits.write(&vec![Hit::NONE; ray_count as usize])?;
                rec = self.gpu.recorder(StreamKind::Main)?;
            }
        }
        let done = rec.submit(after)?;
        self.last_use = Some(done.clone());
        Ok(done)
    }
}

impl Drop for RayQueryTracer {
    fn drop(&mut self) {
        if let Some(p) = self.last_use.take() {
            let _ = self.gpu.wait(&p);
        }
    }
}
