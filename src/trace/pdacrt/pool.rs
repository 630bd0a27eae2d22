//! A pool of device buffers for the level lists, so that the lists of each level reuse
//! the memory the previous levels released instead of allocating anew (Algorithm 1
//! line 16 frees a level; here its buffers return to the pool).
//!
//! Reuse is safe without waits because every PDACRT submission goes to one in-order
//! stream: work that takes a buffer back out of the pool runs after the work that last
//! used it.

use std::collections::BTreeMap;

use crate::vk::{self, Buffer, Gpu, MemoryKind};

pub struct BufferPool {
    gpu: Gpu,
    /// Free buffers by capacity in bytes (powers of two).
    free: BTreeMap<u64, Vec<Buffer>>,
}

impl BufferPool {
    pub fn new(gpu: &Gpu) -> Self {
        Self {
            gpu: gpu.clone(),
            free: BTreeMap::new(),
        }
    }

    /// A buffer of at least `bytes` bytes (contents undefined): the smallest free one
    /// that fits, else a new one of the next power of two.
    pub fn take(&mut self, name: &str, bytes: u64) -> vk::Result<Buffer> {
        let capacity = bytes.max(256).next_power_of_two();
        let fit = self
            .free
            .range(bytes.max(1)..)
            .find(|(_, v)| !v.is_empty())
            .map(|(k, _)| *k);
        if let Some(buffer) = fit.and_then(|k| self.free.get_mut(&k)).and_then(Vec::pop) {
            return Ok(buffer);
        }
        let limit = self.gpu.info().limits.max_storage_buffer_range;
        // Past the largest power of two a binding allows, allocate exactly.
        let capacity = if capacity > limit { bytes } else { capacity };
        self.gpu.create_buffer(name, capacity, MemoryKind::Device)
    }

    /// Returns a buffer for reuse.
    pub fn give(&mut self, buffer: Buffer) {
        self.free.entry(buffer.size()).or_default().push(buffer);
    }

    /// Frees every pooled buffer (the device memory goes back to the allocator).
    pub fn clear(&mut self) {
        self.free.clear();
    }
}
