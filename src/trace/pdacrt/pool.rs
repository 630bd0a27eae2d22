//! A pool of device buffers for the level lists, so that the lists of each level reuse
//! the memory the previous levels released instead of allocating anew (Algorithm 1
//! line 16 frees a level; here its buffers return to the pool).
//!
//! Reuse is safe without waits because every PDACRT submission goes to one in-order
//! stream: work that takes a buffer back out of the pool runs after the work that last
//! used it. Freeing is not: a buffer the pool lets go is only retired, and dropped at
//! the tracer's next host wait ([`BufferPool::collect`]).
//!
//! Peak memory is the point of the pool (the issue's < 64 MB target), so it wastes
//! little: capacities round up by at most 1/8 (not to a power of two), and when no free
//! buffer fits a request, the free buffers smaller than it are retired — level lists
//! grow level by level at first, and the outgrown ones would otherwise sit idle until
//! the frame ends.

use std::collections::BTreeMap;

use crate::vk::{self, Buffer, Gpu, MemoryKind};

pub struct BufferPool {
    gpu: Gpu,
    /// Free buffers by capacity in bytes.
    free: BTreeMap<u64, Vec<Buffer>>,
    /// Let go, but possibly still in use by submitted work.
    retired: Vec<Buffer>,
}

/// `bytes` rounded up to a multiple of an eighth of the largest power of two not above
/// it (at least 256), so that requests of similar sizes share buffers while wasting at
/// most 12.5%.
fn capacity_for(bytes: u64) -> u64 {
    let bytes = bytes.max(1);
    let floor_pow2 = 1u64 << (63 - bytes.leading_zeros());
    bytes.next_multiple_of((floor_pow2 / 8).max(256))
}

/// The largest free buffer that may serve a request of `bytes`.
fn largest_to_serve(bytes: u64) -> u64 {
    (2 * bytes).max(SMALL)
}

/// Buffers this small are shared by requests of any size up to them.
const SMALL: u64 = 64 << 10;

impl BufferPool {
    pub fn new(gpu: &Gpu) -> Self {
        Self {
            gpu: gpu.clone(),
            free: BTreeMap::new(),
            retired: Vec::new(),
        }
    }

    /// A buffer of at least `bytes` bytes (contents undefined): the smallest free one
    /// that fits and is at most twice as large (or small), else a new one (and the free
    /// ones too small for it are retired).
    pub fn take(&mut self, name: &str, bytes: u64) -> vk::Result<Buffer> {
        self.take_inner(name, bytes, false)
    }

    /// As [`BufferPool::take`], for a caller that knows no submitted work still uses a
    /// pooled buffer (right after a host wait): when no free buffer serves the request,
    /// every free and retired buffer is freed before the new one is allocated instead of
    /// beside it (take the largest requests first, so that the others can still reuse).
    pub fn take_while_idle(&mut self, name: &str, bytes: u64) -> vk::Result<Buffer> {
        self.take_inner(name, bytes, true)
    }

    fn take_inner(&mut self, name: &str, bytes: u64, idle: bool) -> vk::Result<Buffer> {
        // A free buffer serves requests down to half its size: a small request must not
        // hold a level's big list, which the next level would then allocate anew.
        let fit = self
            .free
            .range(bytes.max(1)..=largest_to_serve(bytes))
            .find(|(_, v)| !v.is_empty())
            .map(|(k, _)| *k);
        if let Some(buffer) = fit.and_then(|k| self.free.get_mut(&k)).and_then(Vec::pop) {
            return Ok(buffer);
        }
        if idle {
            self.clear();
        } else {
            let outgrown = self.free.split_off(&bytes.max(1));
            let smaller = std::mem::replace(&mut self.free, outgrown);
            self.retired.extend(smaller.into_values().flatten());
        }
        let (limit, _) = self.gpu.max_buffer_bytes();
        // Past the largest buffer the device allows, allocate exactly (and be refused
        // with the limit named when even that is too large).
        let capacity = capacity_for(bytes).min(limit).max(bytes);
        self.gpu.create_buffer(name, capacity, MemoryKind::Device)
    }

    /// Returns a buffer for reuse.
    pub fn give(&mut self, buffer: Buffer) {
        self.free.entry(buffer.size()).or_default().push(buffer);
    }

    /// Drops the retired buffers: call only after a host wait that covers all work
    /// submitted so far.
    pub fn collect(&mut self) {
        self.retired.clear();
    }

    /// Frees every pooled buffer (the device memory goes back to the allocator). The
    /// same condition as [`BufferPool::collect`] applies.
    pub fn clear(&mut self) {
        self.free.clear();
        self.retired.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::{capacity_for, largest_to_serve, SMALL};

    #[test]
    fn capacities_round_up_by_at_most_an_eighth() {
        assert_eq!(capacity_for(0), 256);
        assert_eq!(capacity_for(1), 256);
        assert_eq!(capacity_for(256), 256);
        assert_eq!(capacity_for(257), 512);
        assert_eq!(capacity_for(4096), 4096);
        assert_eq!(capacity_for(4097), 4096 + 512);
        assert_eq!(capacity_for(8191), 8192);
        for bytes in [1000u64, 65_537, 3_200_000, 123_456_789] {
            let c = capacity_for(bytes);
            assert!(c >= bytes && c <= bytes + bytes / 8 + 256, "{bytes} -> {c}");
        }
    }

    #[test]
    fn big_buffers_serve_only_requests_of_at_least_half_their_size() {
        assert_eq!(largest_to_serve(3 << 20), 6 << 20);
        assert_eq!(largest_to_serve(1), SMALL);
        assert_eq!(largest_to_serve(SMALL / 2), SMALL);
        assert_eq!(largest_to_serve(SMALL), 2 * SMALL);
    }
}
