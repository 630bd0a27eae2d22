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
    kernel: ComputePipeline,
    tuning: Tuning,
}

impl Gather {
    pub fn new(gpu: &Gpu, tuning: &Tuning) -> Result<Self> {
        Ok(Self {
            setup: Setup::new(gpu)?,
            kernel: compute_pipeline(
                gpu,
                shaders::PRIMITIVES_GATHER,
                4,
                8,
                &[tuning.workgroup_size, tuning.items_per_invocation],
            )?,
            tuning: *tuning,
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
        self.setup
            .record(rec, count, 1, header, [self.tuning.tile(), 0, 0, 0], None)?;
        let (len, flags) = match direction {
            Direction::Gather => (src.size / 4, 0),
            Direction::Scatter => (out.size / 4, 1),
        };
        rec.dispatch_indirect(
            &self.kernel,
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
