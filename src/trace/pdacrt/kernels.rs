//! The PDACRT pipelines and their push constants.

use bytemuck::{Pod, Zeroable};

use super::{FlushReduce, LevelSplit, PdacrtParams};
use crate::shaders;
use crate::vk::{self, ComputePipeline, Gpu};

const WORKGROUP: u32 = 64;
/// Invocations of level_plan.comp's one workgroup on GPUs.
const PLAN_WORKGROUP_GPU: u32 = 256;

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
    pub left_base: u32,
    pub right_base: u32,
    /// 1: bound each child's triangles ([`PdacrtParams::tight_boxes`]).
    pub tight: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct FilterRaysPush {
    pub n: u32,
    pub eps: f32,
    pub occlusion: u32,
    pub ray_offset: u32,
    pub left_base: u32,
    pub right_base: u32,
    pub tight: u32,
    pub hits_written: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct MaxRunsPush {
    pub max_runs: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct UpdateHitsPush {
    pub max_runs: u32,
    pub ray_offset: u32,
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
    pub tile_items: u32,
    pub tri_left_base: u32,
    pub tri_right_base: u32,
    pub ray_left_base: u32,
    pub ray_right_base: u32,
    /// 1: children take their triangles' bounds as their boxes.
    pub tight: u32,
    /// [`PdacrtParams::terminal_cost`] (0: the paper's β test).
    pub terminal_cost: u32,
}

/// level_plan.comp's push: the children's, and the words of the side-count arrays.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct LevelPlanPush {
    pub children: ChildrenPush,
    pub ranks_len: u32,
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
    pub tile_items: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct ScatterPush {
    pub n: u32,
    pub rays: u32,
    pub left_base: u32,
    pub right_base: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct IntersectPush {
    pub segment_count: u32,
    pub ray_offset: u32,
    /// 1 in occlusion mode.
    pub occlusion: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub struct FinalizePush {
    pub n: u32,
    pub ray_offset: u32,
}

pub struct Kernels {
    pub iota: ComputePipeline,
    pub iota_ids: ComputePipeline,
    pub filter_triangles: ComputePipeline,
    pub filter_rays: ComputePipeline,
    pub child_counts: ComputePipeline,
    pub children: ComputePipeline,
    pub level_summary: ComputePipeline,
    pub level_plan: ComputePipeline,
    pub write_nodes: ComputePipeline,
    pub scatter: ComputePipeline,
    pub segmented_intersect: ComputePipeline,
    pub update_hits: ComputePipeline,
    pub finalize_hits: ComputePipeline,
}

impl Kernels {
    /// N, T and the staging choice of `params` shape the segmented intersection.
    pub fn new(gpu: &Gpu, params: &PdacrtParams) -> vk::Result<Self> {
        let make = |kernel, bindings, push: usize, spec: &[u32]| {
            vk::compute_pipeline(gpu, kernel, bindings, push as u32, spec)
        };
        let wg = &[WORKGROUP];
        // The prefix-sum split binds the rank array to the filters and the scatter
        // instead of the per-node count tables to `children` (see the `ranked` variants).
        let ranked = params.split == LevelSplit::PrefixSums;
        let pick = |sorted, ranked_variant| if ranked { ranked_variant } else { sorted };
        // The ranked filters and scatter take a tile per workgroup; the sorted ones an
        // element per invocation.
        let tile_wg = &[if ranked {
            params.tile_workgroup
        } else {
            WORKGROUP
        }];
        let atomic = params.flush_reduce == FlushReduce::AtomicMin;
        Ok(Self {
            iota: make(shaders::TRACE_PDACRT_IOTA, 2, size_of::<IotaPush>(), wg)?,
            iota_ids: make(
                shaders::TRACE_PDACRT_IOTA__IDS_ONLY,
                1,
                size_of::<IotaPush>(),
                wg,
            )?,
            filter_triangles: make(
                pick(
                    shaders::TRACE_PDACRT_FILTER_TRIANGLES,
                    shaders::TRACE_PDACRT_FILTER_TRIANGLES__RANKED,
                ),
                5 + ranked as u32, // ranked: tiles for keys, and the ranks; the bounds
                size_of::<FilterTrianglesPush>(),
                tile_wg,
            )?,
            filter_rays: make(
                pick(
                    shaders::TRACE_PDACRT_FILTER_RAYS,
                    shaders::TRACE_PDACRT_FILTER_RAYS__RANKED,
                ),
                6 + ranked as u32, // ranked: the ranks; the bounds
                size_of::<FilterRaysPush>(),
                tile_wg,
            )?,
            child_counts: make(
                shaders::TRACE_PDACRT_CHILD_COUNTS,
                4,
                size_of::<MaxRunsPush>(),
                wg,
            )?,
            children: make(
                pick(
                    shaders::TRACE_PDACRT_CHILDREN,
                    shaders::TRACE_PDACRT_CHILDREN__RANKED,
                ),
                6 - ranked as u32, // the last: the children's bounds
                size_of::<ChildrenPush>(),
                wg,
            )?,
            level_summary: make(
                shaders::TRACE_PDACRT_LEVEL_SUMMARY,
                3,
                size_of::<SummaryPush>(),
                &[],
            )?,
            // One subgroup on CPU devices, like the tile kernels (lavapipe switches
            // between a workgroup's subgroups at every barrier); 256 invocations on
            // GPUs, so that a 16K-word scan is 64 items per invocation, not 256.
            level_plan: make(
                shaders::TRACE_PDACRT_LEVEL_PLAN,
                7,
                size_of::<LevelPlanPush>(),
                &[if gpu.info().is_cpu() {
                    params.tile_workgroup
                } else {
                    PLAN_WORKGROUP_GPU
                }],
            )?,
            write_nodes: make(
                pick(
                    shaders::TRACE_PDACRT_WRITE_NODES,
                    shaders::TRACE_PDACRT_WRITE_NODES__RANKED,
                ),
                5 + 2 * ranked as u32, // ranked: the next level's triangle and ray tiles
                size_of::<WriteNodesPush>(),
                wg,
            )?,
            scatter: make(
                pick(
                    shaders::TRACE_PDACRT_SCATTER_ELEMENTS,
                    shaders::TRACE_PDACRT_SCATTER_ELEMENTS__RANKED,
                ),
                6, // ranked: tiles for keys, ranks for the next level's keys
                size_of::<ScatterPush>(),
                tile_wg,
            )?,
            segmented_intersect: make(
                match (params.stage_triangles, atomic) {
                    (true, false) => shaders::TRACE_PDACRT_SEGMENTED_INTERSECT,
                    (false, false) => shaders::TRACE_PDACRT_SEGMENTED_INTERSECT__DIRECT,
                    (true, true) => shaders::TRACE_PDACRT_SEGMENTED_INTERSECT__ATOMIC,
                    (false, true) => shaders::TRACE_PDACRT_SEGMENTED_INTERSECT__DIRECT_ATOMIC,
                },
                7 - atomic as u32,
                size_of::<IntersectPush>(),
                &[params.intersect_workgroup, params.batch],
            )?,
            update_hits: make(
                shaders::TRACE_PDACRT_UPDATE_HITS,
                5,
                size_of::<UpdateHitsPush>(),
                wg,
            )?,
            finalize_hits: make(
                shaders::TRACE_PDACRT_FINALIZE_HITS,
                3,
                size_of::<FinalizePush>(),
                wg,
            )?,
        })
    }
}
