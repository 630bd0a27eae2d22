//! The PDACRT pipelines and their push constants.

use bytemuck::{Pod, Zeroable};

use super::{FlushReduce, LevelSplit, PdacrtParams};
use crate::shaders::{self, Kernel};
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
        let split = SplitVariant::of(params);
        let [iota, iota_ids] = id_kernels(gpu)?;
        let [filter_triangles, filter_rays] = filter_kernels(gpu, split)?;
        let [child_counts, children, level_summary, level_plan, write_nodes] =
            node_kernels(gpu, params, split)?;
        let scatter = make(
            gpu,
            split.pick(
                shaders::TRACE_PDACRT_SCATTER_ELEMENTS,
                shaders::TRACE_PDACRT_SCATTER_ELEMENTS__RANKED,
            ),
            6, // ranked: tiles for keys, ranks for the next level's keys
            size_of::<ScatterPush>(),
            &[split.tile_workgroup],
        )?;
        let [segmented_intersect, update_hits, finalize_hits] = intersection_kernels(gpu, params)?;
        Ok(Self {
            iota,
            iota_ids,
            filter_triangles,
            filter_rays,
            child_counts,
            children,
            level_summary,
            level_plan,
            write_nodes,
            scatter,
            segmented_intersect,
            update_hits,
            finalize_hits,
        })
    }
}

/// Which kernels split a level: the sorted ones or the `ranked` variants.
#[derive(Clone, Copy)]
struct SplitVariant {
    /// The prefix-sum split binds the rank array to the filters and the scatter
    /// instead of the per-node count tables to `children` (see the `ranked` variants).
    ranked: bool,
    /// The ranked filters and scatter take a tile per workgroup; the sorted ones an
    /// element per invocation.
    tile_workgroup: u32,
}

impl SplitVariant {
    fn of(params: &PdacrtParams) -> Self {
        let ranked = params.split == LevelSplit::PrefixSums;
        Self {
            ranked,
            tile_workgroup: if ranked {
                params.tile_workgroup
            } else {
                WORKGROUP
            },
        }
    }

    fn pick(self, sorted: Kernel, ranked_variant: Kernel) -> Kernel {
        if self.ranked {
            ranked_variant
        } else {
            sorted
        }
    }
}

fn make(
    gpu: &Gpu,
    kernel: Kernel,
    bindings: u32,
    push: usize,
    spec: &[u32],
) -> vk::Result<ComputePipeline> {
    vk::compute_pipeline(gpu, kernel, bindings, push as u32, spec)
}

/// The kernels that fill the root's id lists: `iota` and `iota_ids`.
fn id_kernels(gpu: &Gpu) -> vk::Result<[ComputePipeline; 2]> {
    let wg = &[WORKGROUP];
    Ok([
        make(
            gpu,
            shaders::TRACE_PDACRT_IOTA,
            2,
            size_of::<IotaPush>(),
            wg,
        )?,
        make(
            gpu,
            shaders::TRACE_PDACRT_IOTA__IDS_ONLY,
            1,
            size_of::<IotaPush>(),
            wg,
        )?,
    ])
}

/// The triangles' and the rays' filters against the children.
fn filter_kernels(gpu: &Gpu, split: SplitVariant) -> vk::Result<[ComputePipeline; 2]> {
    let ranked = split.ranked as u32;
    let tile_wg = &[split.tile_workgroup];
    Ok([
        make(
            gpu,
            split.pick(
                shaders::TRACE_PDACRT_FILTER_TRIANGLES,
                shaders::TRACE_PDACRT_FILTER_TRIANGLES__RANKED,
            ),
            5 + ranked, // ranked: tiles for keys, and the ranks; the bounds
            size_of::<FilterTrianglesPush>(),
            tile_wg,
        )?,
        make(
            gpu,
            split.pick(
                shaders::TRACE_PDACRT_FILTER_RAYS,
                shaders::TRACE_PDACRT_FILTER_RAYS__RANKED,
            ),
            6 + ranked, // ranked: the ranks; the bounds
            size_of::<FilterRaysPush>(),
            tile_wg,
        )?,
    ])
}

/// The kernels that make the next level's nodes: `child_counts`, `children`,
/// `level_summary`, `level_plan` and `write_nodes`.
fn node_kernels(
    gpu: &Gpu,
    params: &PdacrtParams,
    split: SplitVariant,
) -> vk::Result<[ComputePipeline; 5]> {
    let wg = &[WORKGROUP];
    let ranked = split.ranked as u32;
    Ok([
        make(
            gpu,
            shaders::TRACE_PDACRT_CHILD_COUNTS,
            4,
            size_of::<MaxRunsPush>(),
            wg,
        )?,
        make(
            gpu,
            split.pick(
                shaders::TRACE_PDACRT_CHILDREN,
                shaders::TRACE_PDACRT_CHILDREN__RANKED,
            ),
            6 - ranked, // the last: the children's bounds
            size_of::<ChildrenPush>(),
            wg,
        )?,
        make(
            gpu,
            shaders::TRACE_PDACRT_LEVEL_SUMMARY,
            3,
            size_of::<SummaryPush>(),
            &[],
        )?,
        // One subgroup on CPU devices, like the tile kernels (lavapipe switches
        // between a workgroup's subgroups at every barrier); 256 invocations on
        // GPUs, so that a 16K-word scan is 64 items per invocation, not 256.
        make(
            gpu,
            shaders::TRACE_PDACRT_LEVEL_PLAN,
            7,
            size_of::<LevelPlanPush>(),
            &[if gpu.info().is_cpu() {
                params.tile_workgroup
            } else {
                PLAN_WORKGROUP_GPU
            }],
        )?,
        make(
            gpu,
            split.pick(
                shaders::TRACE_PDACRT_WRITE_NODES,
                shaders::TRACE_PDACRT_WRITE_NODES__RANKED,
            ),
            5 + 2 * ranked, // ranked: the next level's triangle and ray tiles
            size_of::<WriteNodesPush>(),
            wg,
        )?,
    ])
}

/// The leaves' kernels: `segmented_intersect`, `update_hits` and `finalize_hits`.
fn intersection_kernels(gpu: &Gpu, params: &PdacrtParams) -> vk::Result<[ComputePipeline; 3]> {
    let wg = &[WORKGROUP];
    let atomic = params.flush_reduce == FlushReduce::AtomicMin;
    Ok([
        make(
            gpu,
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
        make(
            gpu,
            shaders::TRACE_PDACRT_UPDATE_HITS,
            5,
            size_of::<UpdateHitsPush>(),
            wg,
        )?,
        make(
            gpu,
            shaders::TRACE_PDACRT_FINALIZE_HITS,
            3,
            size_of::<FinalizePush>(),
            wg,
        )?,
    ])
}
