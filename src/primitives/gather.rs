//! Gather (`out[i] = src[idx[i]]`) and scatter (`out[idx[i]] = src[i]`) of u32 by index.

use super::{args_offset, check_scratch, Count, Setup, Tuning, HEADER_BYTES};
use crate::shaders;
use crate::vk::{compute_pipeline, Buffer, BufferSlice, ComputePipeline, Gpu, Recorder, Result};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GatherPush {
    len: u32,
    flags: u32,
}

/// Direction of the indexed move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// `out[i] = src[idx[i]]`; indices `>= src` length read as 0.
    Gather,
    /// `out[idx[i]] = src[i]`; indices `>= out` length are skipped. With repeated
    /// indices one of the writers wins (unspecified which).
    Scatter,
}

pub struct Gather {
    setup: Setup,
    /// The kernel and its items per workgroup, for gathers and for scatters.
    gather: (ComputePipeline, u32),
    scatter: (ComputePipeline, u32),
}

impl Gather {
    pub fn new(gpu: &Gpu, tuning: &Tuning) -> Result<Self> {
        let rows = |gpu| -> Result<(ComputePipeline, u32)> {
            let items = tuning.items_per_invocation;
            let kernel = shaders::PRIMITIVES_GATHER;
            let pipeline = compute_pipeline(gpu, kernel, 4, 8, &[tuning.workgroup_size, items])?;
            Ok((pipeline, tuning.workgroup_size * items))
        };
        // With 64-bit accesses (CPU devices) a gather moves segments of the scan's
        // length: 2.0-2.2x faster than subgroup rows on lavapipe (4M random indices,
        // medians of 15 alternating runs, two runs: 26.9 / 33.3 against 59.6 / 67.1
        // ms). The scatter keeps the rows, which measured 7% faster there (14.8 / 14.9
        // against 15.8 / 16.2 ms): its cost is the random stores either way.
        let segment = tuning.scan_segment;
        let gather = if tuning.wide_segments(gpu.info(), segment) {
            let kernel = shaders::PRIMITIVES_GATHER__SEG64;
            let pipeline = compute_pipeline(gpu, kernel, 4, 8, &[tuning.workgroup_size, segment])?;
            (pipeline, tuning.workgroup_size * segment)
        } else {
            rows(gpu)?
        };
        Ok(Self {
            setup: Setup::new(gpu)?,
            gather,
            scatter: rows(gpu)?,
        })
    }

    /// Scratch bytes (the header only, whatever n).
    pub fn scratch_bytes(&self, _max_n: u32) -> u64 {
        HEADER_BYTES
    }

    /// Moves the first `n` items. Inputs must be visible to compute reads; ends with a
    /// barrier.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        n: u32,
        direction: Direction,
        src: BufferSlice<'_>,
        idx: BufferSlice<'_>,
        out: BufferSlice<'_>,
        scratch: &Buffer,
    ) -> Result<()> {
        self.record_count(rec, Count::Host(n), direction, src, idx, out, scratch)
    }

    /// As [`Gather::record`], with n read on the GPU from the u32 at byte `count_offset`
    /// of `count`, clamped to `max_n`.
    #[allow(clippy::too_many_arguments)]
    pub fn record_indirect(
        &self,
        rec: &mut Recorder,
        count: &Buffer,
        count_offset: u64,
        max_n: u32,
        direction: Direction,
        src: BufferSlice<'_>,
        idx: BufferSlice<'_>,
        out: BufferSlice<'_>,
        scratch: &Buffer,
    ) -> Result<()> {
        let count = Count::Gpu {
            buffer: count,
            offset: count_offset,
            max: max_n,
        };
        self.record_count(rec, count, direction, src, idx, out, scratch)
    }

    #[allow(clippy::too_many_arguments)]
    fn record_count(
        &self,
        rec: &mut Recorder,
        count: Count<'_>,
        direction: Direction,
        src: BufferSlice<'_>,
        idx: BufferSlice<'_>,
        out: BufferSlice<'_>,
        scratch: &Buffer,
    ) -> Result<()> {
        check_scratch("gather", scratch, 0, HEADER_BYTES)?;
        let header = scratch.slice(0, HEADER_BYTES);
        let ((kernel, tile), len, flags) = match direction {
            Direction::Gather => (&self.gather, src.size / 4, 0),
            Direction::Scatter => (&self.scatter, out.size / 4, 1),
        };
        self.setup
            .record(rec, count, 1, header, [*tile, 0, 0, 0], None)?;
        rec.dispatch_indirect(
            kernel,
            &[header, src, idx, out],
            &GatherPush {
                len: len.min(u32::MAX as u64) as u32,
                flags,
            },
            scratch,
            args_offset(0),
        )?;
        rec.barrier();
        Ok(())
    }
}
