//! Material sorting of a wavefront's live paths (thesis §4.4.2): each path's hit gets
//! its material key's rank (`sort_keys.comp`; misses sort last), and a radix sort orders
//! the path positions by it — the order of the 32-bit keys (type, then id) in the few
//! bits a scene's materials need ([`sort_ranks`]) — so that shading kernels read
//! `order` and neighbouring invocations evaluate the same material. Shared by `pt` and
//! the light-vertex-cache integrators, whose wavefronts hold the same hit and order
//! buffers.

use super::gpu::PtParams;
use super::materials::sort_rank_bits;
#[cfg(doc)]
use super::materials::sort_ranks;
use super::SceneBuffers;
use crate::primitives::radix_sort::SortScratch;
use crate::primitives::{RadixSort, Tuning};
use crate::shaders;
use crate::vk::{self, Buffer, ComputePipeline, Gpu, Recorder};

/// The key kernel, the sort and its scratch for up to `capacity` paths.
pub(crate) struct MaterialSort {
    keys_kernel: ComputePipeline,
    sort: RadixSort,
    scratch: SortScratch,
}

impl MaterialSort {
    pub(crate) fn new(gpu: &Gpu, tuning: &Tuning, capacity: u32) -> vk::Result<Self> {
        let sort = RadixSort::new(gpu, tuning)?;
        let scratch = sort.alloc_scratch(gpu, capacity)?;
        Ok(Self {
            keys_kernel: vk::compute_pipeline(
                gpu,
                shaders::INTEGRATOR_PT_SORT_KEYS,
                5,
                size_of::<PtParams>() as u32,
                &[super::WORKGROUP],
            )?,
            sort,
            scratch,
        })
    }

    /// Records, for the first `n` paths: their key ranks from `hits` into `keys`, then
    /// `order` (their positions) sorted by them.
    pub(crate) fn record(
        &self,
        rec: &mut Recorder,
        n: u32,
        hits: &Buffer,
        scene: &SceneBuffers,
        keys: &Buffer,
        order: &Buffer,
    ) -> vk::Result<()> {
        rec.dispatch_items(
            &self.keys_kernel,
            &[
                hits.into(),
                (&scene.triangle_material).into(),
                (&scene.materials).into(),
                keys.into(),
                order.into(),
            ],
            &PtParams {
                active_count: n,
                ..Default::default()
            },
            n as u64,
        )?;
        rec.barrier();
        self.sort.record(
            rec,
            n,
            keys.into(),
            Some(order.into()),
            0..sort_rank_bits(scene.material_count),
            &self.scratch,
        )
    }
}
