//! The light vertex cache (Davidovič et al. 2014; thesis §4.3): every connectible surface
//! vertex of a chunk's light subpaths, never dropped and never overwritten.
//!
//! **Sizing.** A prepass traces a fraction of the light paths
//! ([`super::plan::prepass_paths`]) and measures v̄, the mean number of cached vertices
//! per light path; a chunk of P light
//! paths gets ⌈1.1 · v̄ · P⌉ + 64 slots (the thesis's 1.1 × the average, and room for the
//! fluctuation of small chunks). A light pass that needs more slots than that writes
//! none past the end, reports how many it needed, and the caller grows the cache to fit
//! and runs the pass again ([`LightCache::grow`]): the pass is a pure function of its
//! random numbers, so the second run stores the same vertices.
//!
//! **Layout.** The light pass writes vertices in the order they are made: bounce by
//! bounce, in the active list's order (which compaction keeps), so the content is the
//! same on every device. Each light path counts its vertices; an exclusive prefix sum of
//! the counts gives each path its slots, and [`LightCache::record_index`] writes the
//! per-path slots of an index (count → prefix sum → write): pass q's vertices are index
//! entries `path_offset[q N_L] .. path_offset[(q + 1) N_L]`, each light path's
//! contiguous and in order, whichever bounce made them. Selection reads through the
//! index, so the cache content a camera path sees depends on its pass alone, not on how
//! passes were grouped into chunks.

use super::gpu::{LvcPush, LvcVertex};
use super::kernels::Kernels;
use crate::primitives::{Scan, ScanKind, Tuning};
use crate::vk::{self, Buffer, Gpu, MemoryKind, Recorder};

/// Slots for `paths` light paths of `per_path` cached vertices each on average.
pub fn capacity_for(paths: u32, per_path: f64) -> u64 {
    (1.1 * per_path * paths as f64).ceil() as u64 + 64
}

pub struct LightCache {
    /// The vertices, in the order the light pass made them.
    pub vertices: Buffer,
    /// Per-path slots: entry `path_offset[l] + o` is the cache slot of light path l's
    /// o-th vertex.
    pub index: Buffer,
    /// Slots a light pass may fill (the buffers may hold more).
    pub capacity: u32,
    /// Per light path of a chunk (and one more, zero): its cached vertices.
    pub vertex_count: Buffer,
    /// The exclusive prefix sum of `vertex_count`.
    pub path_offset: Buffer,
    scan: Scan,
    scan_scratch: Buffer,
    max_paths: u32,
}

impl LightCache {
    /// A cache of `capacity` slots for chunks of up to `max_paths` light paths.
    pub fn new(gpu: &Gpu, capacity: u32, max_paths: u32) -> vk::Result<Self> {
        let scan = Scan::new(gpu, &Tuning::for_device(gpu.info()))?;
        let entries = max_paths as usize + 1;
        Ok(Self {
            vertices: gpu.zeroed::<LvcVertex>("lvc-cache", capacity.max(1) as usize)?,
            index: gpu.zeroed::<u32>("lvc-cache-index", capacity.max(1) as usize)?,
            capacity: capacity.max(1),
            vertex_count: gpu.zeroed::<u32>("lvc-vertex-count", entries)?,
            path_offset: gpu.zeroed::<u32>("lvc-path-offset", entries)?,
            scan_scratch: gpu.create_buffer(
                "lvc-scan-scratch",
                scan.scratch_bytes(entries as u32),
                MemoryKind::Device,
            )?,
            scan,
            max_paths,
        })
    }

    /// Raises the capacity to `needed` slots and 10% more (the caller waits for the GPU
    /// to be done with the old buffers first: [`LightCache::set_capacity`]).
    pub fn grow(&mut self, gpu: &Gpu, needed: u64) -> vk::Result<()> {
        let limit = gpu.info().limits.max_storage_buffer_range / size_of::<LvcVertex>() as u64;
        if needed > limit.min(u32::MAX as u64) {
            return Err(vk::VkError::Usage(format!(
                "a chunk's light subpaths made {needed} cache vertices, more than one \
                 storage-buffer binding holds ({limit}): use fewer light paths per pass"
            )));
        }
        self.set_capacity(gpu, (needed + needed / 10 + 64).min(limit))
    }

    /// Sets the capacity to `capacity` slots (at most what one binding holds). The
    /// vertex and index buffers are replaced only when they hold fewer (the caller waits
    /// for the GPU to be done with them first): a cache sized for an earlier frame of an
    /// animation keeps its buffers, while its capacity — which decides when a light pass
    /// grows the cache and runs again, and so the rays traced — is the one a render of
    /// this frame alone would have.
    pub fn set_capacity(&mut self, gpu: &Gpu, capacity: u64) -> vk::Result<()> {
        let limit = gpu.info().limits.max_storage_buffer_range / size_of::<LvcVertex>() as u64;
        let capacity = capacity.clamp(1, limit.min(u32::MAX as u64));
        if capacity > self.slots() {
            self.vertices = gpu.zeroed::<LvcVertex>("lvc-cache", capacity as usize)?;
            self.index = gpu.zeroed::<u32>("lvc-cache-index", capacity as usize)?;
        }
        self.capacity = capacity as u32;
        Ok(())
    }

    /// Slots the vertex and index buffers hold (the capacity or more).
    fn slots(&self) -> u64 {
        (self.vertices.size() / size_of::<LvcVertex>() as u64)
            .min(self.index.size() / size_of::<u32>() as u64)
    }

    /// Records the per-path index of a chunk of `paths` light paths that stored `total`
    /// vertices: `path_offset` = exclusive prefix sum of the counts (the entry after
    /// the last path is zero, so `path_offset[paths]` = `total`), then each vertex
    /// writes its slot. The counts must be visible to compute reads.
    pub fn record_index(
        &self,
        rec: &mut Recorder,
        kernels: &Kernels,
        paths: u32,
        total: u32,
    ) -> vk::Result<()> {
        debug_assert!(paths <= self.max_paths);
        self.scan.record(
            rec,
            paths + 1,
            (&self.vertex_count).into(),
            (&self.path_offset).into(),
            ScanKind::Exclusive,
            &self.scan_scratch,
        )?;
        let push = LvcPush {
            active_count: total,
            ..Default::default()
        };
        rec.dispatch_items(
            &kernels.light_index,
            &[
                (&self.vertices).into(),
                (&self.path_offset).into(),
                (&self.index).into(),
            ],
            &push,
            total as u64,
        )?;
        rec.barrier();
        Ok(())
    }
}
