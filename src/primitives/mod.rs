//! Data-parallel primitives on GLSL compute (issue 3): prefix scan, stable LSD radix
//! sort of key-value pairs, reduce-by-key (sum, arg-min), run-length encoding, stream
//! compaction, gather and scatter — each with a CPU twin in [`cpu`].
//!
//! # Contract shared by every primitive
//! - `Xxx::new(&gpu, &tuning)` creates the primitive's pipelines and nothing else.
//! - `scratch_bytes(max_n)` says how much scratch one recording needs for up to `max_n`
//!   items; the caller allocates it (any [`Buffer`], e.g. `gpu.create_buffer(..,
//!   MemoryKind::Device)`) and may reuse it across recordings that do not overlap on the
//!   GPU. The radix sort also needs two `max_n`-word ping-pong buffers
//!   ([`RadixSort::alloc_scratch`]).
//! - `record(rec, n, ...)` records into the caller's [`Recorder`]; `record_indirect(rec,
//!   count, count_offset, max_n, ...)` reads n from the u32 at `count_offset` of `count`
//!   *when the work runs* (clamped to `max_n`), so a level loop never reads counts back.
//!   Both share one code path: a one-invocation setup kernel writes n and the indirect
//!   dispatch arguments into the scratch header, and every pass is a
//!   `dispatch_indirect`.
//! - Barriers: the caller owes one `rec.barrier()` between writing the inputs (or the
//!   count) on the GPU and the recording; `record*` places barriers between its own
//!   passes and ends with one, so its outputs are visible to whatever is recorded next.
//! - Slices handed to kernels must start at a multiple of the device's
//!   `minStorageBufferOffsetAlignment`; whole buffers always do.
//! - Counts and indices are u32; sums wrap modulo 2^32 like `u32::wrapping_add`.

pub mod compact;
pub mod cpu;
pub mod gather;
pub mod radix_sort;
pub mod reduce_by_key;
pub mod scan;
pub mod tuning;

pub use compact::Compact;
pub use gather::Gather;
pub use radix_sort::{RadixSort, SortScratch};
pub use reduce_by_key::ReduceByKey;
pub use scan::{Scan, ScanKind};
pub use tuning::Tuning;

use crate::vk::{
    compute_pipeline, Buffer, BufferSlice, ComputePipeline, Gpu, Recorder, Result, VkError,
};

/// Bytes of the scratch header that the setup kernel writes (n, group counts, indirect
/// arguments); also the alignment of every region inside a scratch buffer.
pub(crate) const HEADER_BYTES: u64 = 256;

/// Byte offset of the indirect arguments of dispatch kind `k` inside a header.
pub(crate) fn args_offset(k: u32) -> u64 {
    (8 + 4 * k as u64) * 4
}

/// Rounds a region size up to the scratch alignment.
pub(crate) fn region(bytes: u64) -> u64 {
    bytes.max(4).next_multiple_of(HEADER_BYTES)
}

/// Where a recording finds n.
#[derive(Clone, Copy, Debug)]
pub enum Count<'a> {
    /// Known on the host when recording.
    Host(u32),
    /// The u32 at byte `offset` of `buffer`, read when the work runs, clamped to `max`.
    Gpu {
        buffer: &'a Buffer,
        offset: u64,
        max: u32,
    },
}

impl Count<'_> {
    /// The capacity the scratch must be laid out for.
    pub fn capacity(&self) -> u32 {
        match *self {
            Count::Host(n) => n,
            Count::Gpu { max, .. } => max,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct SetupPush {
    n: u32,
    count_word: u32,
    flags: u32,
    max_n: u32,
    mul: u32,
    max_x: u32,
    items: [u32; 4],
}

/// The one-invocation kernel that starts every recording (see the module docs).
pub(crate) struct Setup {
    pipeline: ComputePipeline,
}

impl Setup {
    pub(crate) fn new(gpu: &Gpu) -> Result<Self> {
        let align = gpu.info().limits.min_storage_buffer_offset_alignment;
        if align > HEADER_BYTES {
            return Err(VkError::Usage(format!(
                "primitives: minStorageBufferOffsetAlignment {align} exceeds {HEADER_BYTES}"
            )));
        }
        Ok(Self {
            pipeline: compute_pipeline(gpu, crate::shaders::PRIMITIVES_SETUP, 3, 40, &[1])?,
        })
    }

    /// Writes the header at `header` (a [`HEADER_BYTES`] slice): n from `count`
    /// (multiplied by `mul` when read on the GPU) and the groups of up to four dispatch
    /// kinds of `items[k]` items per workgroup. `zero` gets a 0 written to its first
    /// word. Ends with a barrier.
    pub(crate) fn record(
        &self,
        rec: &mut Recorder,
        count: Count<'_>,
        mul: u32,
        header: BufferSlice<'_>,
        items: [u32; 4],
        zero: Option<BufferSlice<'_>>,
    ) -> Result<()> {
        let max_x = rec.gpu().info().limits.max_compute_work_group_count[0];
        let (src, n, count_word, mut flags, max_n) = match count {
            Count::Host(n) => (header, n, 0, 0, n),
            Count::Gpu {
                buffer,
                offset,
                max,
            } => {
                if offset % 4 != 0 {
                    return Err(VkError::Usage(format!(
                        "count offset {offset} is not a multiple of 4"
                    )));
                }
                (BufferSlice::from(buffer), 0, (offset / 4) as u32, 1, max)
            }
        };
        if zero.is_some() {
            flags |= 2;
        }
        let push = SetupPush {
            n,
            count_word,
            flags,
            max_n,
            mul,
            max_x,
            items,
        };
        rec.dispatch(
            &self.pipeline,
            &[src, header, zero.unwrap_or(header)],
            &push,
            [1, 1, 1],
        )?;
        rec.barrier();
        Ok(())
    }
}

/// Checks that a caller's scratch buffer is big enough.
pub(crate) fn check_scratch(what: &str, scratch: &Buffer, base: u64, needed: u64) -> Result<()> {
    if scratch.size() < base + needed {
        return Err(VkError::Usage(format!(
            "{what}: scratch '{}' holds {} bytes, {} needed",
            scratch.name(),
            scratch.size(),
            base + needed
        )));
    }
    Ok(())
}
