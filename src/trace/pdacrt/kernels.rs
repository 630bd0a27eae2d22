//! The PDACRT pipelines and their push constants.

use bytemuck::{Pod, Zeroable};

use crate::shaders;
use crate::vk::{self, ComputePipeline, Gpu, PipelineDesc};

const WORKGROUP: u32 = 64;

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct IotaPush {
    pub n: u32,
    pub base: u32,
    pub tag: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct FilterTrianglesPush {
    pub n: u32,
    pub eps: f32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct FilterRaysPush {
    pub n: u32,
    pub eps: f32,
    pub occlusion: u32,
    pub ray_offset: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct MaxRunsPush {
    pub max_runs: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct ChildrenPush {
    pub child_count: u32,
    pub stride: u32,
    pub alpha: u32,
    pub beta: u32,
    pub last_level: u32,
    pub min_extent: f32,
    pub max_segment_rays: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct SummaryPush {
    pub child_count: u32,
    pub stride: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct WriteNodesPush {
    pub child_count: u32,
    pub stride: u32,
    pub segment_base: u32,
    pub term_tri_base: u32,
    pub term_ray_base: u32,
    pub max_segment_rays: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct ScatterPush {
    pub n: u32,
    pub stride: u32,
    pub rays: u32,
    pub term_base: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct IntersectPush {
    pub segment_count: u32,
    pub ray_offset: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct FinalizePush {
    pub n: u32,
    pub ray_offset: u32,
}

pub struct Kernels {
    pub iota: ComputePipeline,
    pub filter_triangles: ComputePipeline,
    pub filter_rays: ComputePipeline,
    pub child_counts: ComputePipeline,
    pub children: ComputePipeline,
    pub level_summary: ComputePipeline,
    pub write_nodes: ComputePipeline,
    pub scatter: ComputePipeline,
    pub segmented_intersect: ComputePipeline,
    pub update_hits: ComputePipeline,
    pub finalize_hits: ComputePipeline,
}

impl Kernels {
    /// `intersect_workgroup` (N) and `batch` (T) shape the segmented intersection.
    pub fn new(gpu: &Gpu, intersect_workgroup: u32, batch: u32) -> vk::Result<Self> {
        let make = |kernel, bindings, push: usize, spec: &[u32]| {
            ComputePipeline::new(
                gpu,
                &PipelineDesc {
                    kernel,
                    bindings,
                    push_constant_bytes: push as u32,
                    spec,
                },
            )
        };
        let wg = &[WORKGROUP];
        Ok(Self {
            iota: make(shaders::TRACE_PDACRT_IOTA, 2, size_of::<IotaPush>(), wg)?,
            filter_triangles: make(
                shaders::TRACE_PDACRT_FILTER_TRIANGLES,
                4,
                size_of::<FilterTrianglesPush>(),
                wg,
            )?,
            filter_rays: make(
                shaders::TRACE_PDACRT_FILTER_RAYS,
                6,
                size_of::<FilterRaysPush>(),
                wg,
            )?,
            child_counts: make(
                shaders::TRACE_PDACRT_CHILD_COUNTS,
                4,
                size_of::<MaxRunsPush>(),
                wg,
            )?,
            children: make(
                shaders::TRACE_PDACRT_CHILDREN,
                5,
                size_of::<ChildrenPush>(),
                wg,
            )?,
            level_summary: make(
                shaders::TRACE_PDACRT_LEVEL_SUMMARY,
                3,
                size_of::<SummaryPush>(),
                &[],
            )?,
            write_nodes: make(
                shaders::TRACE_PDACRT_WRITE_NODES,
                4,
                size_of::<WriteNodesPush>(),
                wg,
            )?,
            scatter: make(
                shaders::TRACE_PDACRT_SCATTER_ELEMENTS,
                7,
                size_of::<ScatterPush>(),
                wg,
            )?,
            segmented_intersect: make(
                shaders::TRACE_PDACRT_SEGMENTED_INTERSECT,
                7,
                size_of::<IntersectPush>(),
                &[intersect_workgroup, batch],
            )?,
            update_hits: make(
                shaders::TRACE_PDACRT_UPDATE_HITS,
                6,
                size_of::<MaxRunsPush>(),
                wg,
            )?,
            finalize_hits: make(
                shaders::TRACE_PDACRT_FINALIZE_HITS,
                5,
                size_of::<FinalizePush>(),
                wg,
            )?,
        })
    }
}
