//! Stable stream compaction by a u32 flag array (non-zero = keep): an exclusive
//! [`Scan`] of `(flag != 0)` gives each kept item its slot; the kept count is written
//! to a GPU buffer (readable by the host).
//!
//! With the segment scan ([`Tuning::scan_segment`], CPU devices) only the scan's first
//! two passes run: they give every invocation the kept count before its segment, and a
//! segment kernel then writes each segment's kept items in order. That skips writing
//! and reading back a per-item position array.

use super::{
    args_offset, check_scratch, region, Count, Scan, ScanKind, Setup, Tuning, HEADER_BYTES,
};
use crate::shaders;
use crate::vk::{compute_pipeline, Buffer, BufferSlice, ComputePipeline, Gpu, Recorder, Result};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FlagsPush {
    flags: u32,
}

/// What compaction writes for each kept item.
#[derive(Clone, Copy, Debug)]
pub enum Kept<'a> {
    /// The item of this array.
    Values(BufferSlice<'a>),
    /// Its index i.
    Indices,
}

pub struct Compact {
    setup: Setup,
    scatter: ComputePipeline,
    /// The segment variant's kernel (where the scan runs in segments).
    segment_scatter: Option<ComputePipeline>,
    scan: Scan,
    tuning: Tuning,
}

impl Compact {
    pub fn new(gpu: &Gpu, tuning: &Tuning) -> Result<Self> {
        Ok(Self {
            setup: Setup::new(gpu)?,
            scatter: compute_pipeline(
                gpu,
                shaders::PRIMITIVES_COMPACT_SCATTER,
                6,
                4,
                &[tuning.workgroup_size, tuning.items_per_invocation],
            )?,
            segment_scatter: match Scan::segment(tuning) {
                0 => None,
                items => Some(compute_pipeline(
                    gpu,
                    if Scan::wide(gpu, tuning) {
                        shaders::PRIMITIVES_COMPACT_SEG__WIDE64
                    } else {
                        shaders::PRIMITIVES_COMPACT_SEG
                    },
                    6,
                    4,
                    &[tuning.workgroup_size, items],
                )?),
            },
            scan: Scan::new(gpu, tuning)?,
            tuning: *tuning,
        })
    }

    /// (positions, inner scan) offsets in the scratch. The segment variant has neither
    /// a header of its own nor a position array: its scratch is the scan's.
    fn layout(&self, max_n: u32) -> (u64, u64) {
        if self.segment_scatter.is_some() {
            return (0, 0);
        }
        let pos = HEADER_BYTES;
        (pos, pos + region(max_n as u64 * 4))
    }

    /// Scratch bytes for up to `max_n` items.
    pub fn scratch_bytes(&self, max_n: u32) -> u64 {
        self.layout(max_n).1 + self.scan.scratch_bytes(max_n)
    }

    /// `out[..count]` = the kept items of the first `n`, in order; `count[0]` = how
    /// many. Inputs must be visible to compute reads; ends with a barrier.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        n: u32,
        flags: BufferSlice<'_>,
        kept: Kept<'_>,
        out: BufferSlice<'_>,
        count: BufferSlice<'_>,
        scratch: &Buffer,
    ) -> Result<()> {
        self.record_count(rec, Count::Host(n), flags, kept, out, count, scratch)
    }

    /// As [`Compact::record`], with n read on the GPU from the u32 at byte
    /// `count_offset` of `n_buffer`, clamped to `max_n` (the capacity of `scratch`).
    #[allow(clippy::too_many_arguments)]
    pub fn record_indirect(
        &self,
        rec: &mut Recorder,
        n_buffer: &Buffer,
        count_offset: u64,
        max_n: u32,
        flags: BufferSlice<'_>,
        kept: Kept<'_>,
        out: BufferSlice<'_>,
        count: BufferSlice<'_>,
        scratch: &Buffer,
    ) -> Result<()> {
        let n = Count::Gpu {
            buffer: n_buffer,
            offset: count_offset,
            max: max_n,
        };
        self.record_count(rec, n, flags, kept, out, count, scratch)
    }

    #[allow(clippy::too_many_arguments)]
    fn record_count(
        &self,
        rec: &mut Recorder,
        n: Count<'_>,
        flags: BufferSlice<'_>,
        kept: Kept<'_>,
        out: BufferSlice<'_>,
        count: BufferSlice<'_>,
        scratch: &Buffer,
    ) -> Result<()> {
        let cap = n.capacity();
        check_scratch("compaction", scratch, 0, self.scratch_bytes(cap))?;
        let (pos_off, scan_off) = self.layout(cap);
        let (src, mode) = match kept {
            Kept::Values(v) => (v, 0),
            Kept::Indices => (flags, 1),
        };
        if let Some(segment_scatter) = &self.segment_scatter {
            // The scan's header is the only one; its setup also zeroes the count (n = 0).
            self.scan
                .record_setup(rec, n, 1, scratch, scan_off, Some(count))?;
            let offsets = self
                .scan
                .record_tile_offsets(rec, flags, true, cap, scratch, scan_off)?;
            rec.dispatch_indirect(
                segment_scatter,
                &[offsets.header, flags, offsets.sums, src, out, count],
                &FlagsPush { flags: mode },
                scratch,
                offsets.args,
            )?;
            rec.barrier();
            return Ok(());
        }
        let header = scratch.slice(0, HEADER_BYTES);
        self.setup.record(
            rec,
            n,
            1,
            header,
            [self.tuning.tile(), 0, 0, 0],
            Some(count),
        )?;
        let pos = scratch.slice(pos_off, region(cap as u64 * 4));
        self.scan.record_count(
            rec,
            n,
            flags,
            pos,
            ScanKind::Exclusive,
            true,
            scratch,
            scan_off,
        )?;
        rec.dispatch_indirect(
            &self.scatter,
            &[header, flags, pos, src, out, count],
            &FlagsPush { flags: mode },
            scratch,
            args_offset(0),
        )?;
        rec.barrier();
        Ok(())
    }
}
