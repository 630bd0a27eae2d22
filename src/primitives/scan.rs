//! Prefix scan (exclusive or inclusive) of u32, any n: reduce-then-scan in three
//! dispatches — tile sums, one-workgroup scan of the tile sums, then each tile scans
//! itself from its offset. Each invocation works through a contiguous run. With
//! [`Tuning::scan_segment`] (CPU devices) the sums are per invocation instead of per
//! workgroup, so neither big pass has a barrier or a subgroup operation. A scan of at
//! most [`SMALL_SCAN_MAX`] items known on the host is one dispatch of one workgroup.

use super::{args_offset, check_scratch, region, Count, Setup, Tuning, HEADER_BYTES};
use crate::shaders;
use crate::vk::{compute_pipeline, Buffer, BufferSlice, ComputePipeline, Gpu, Recorder, Result};

/// Exclusive (`out[i] = x[0] + .. + x[i-1]`) or inclusive (`.. + x[i]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScanKind {
    Exclusive,
    Inclusive,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FlagsPush {
    flags: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct SmallPush {
    n: u32,
    flags: u32,
}

/// The most items a host-counted scan does in one dispatch of one workgroup
/// (scan_small.comp) instead of three passes. Such short scans are all fixed cost:
/// PDACRT scans two arrays of a few thousand words per level, where the three passes
/// (with the setup, four dispatches and four barriers) took 0.27 ms of each level on
/// lavapipe. At this size one workgroup's runs stay short on every device (2 048 items
/// per invocation at lavapipe's 8 invocations, 16–128 at a GPU's 128–1 024).
pub const SMALL_SCAN_MAX: u32 = 1 << 14;

/// Prefix sums of u32 (wrapping), in place or out of place.
pub struct Scan {
    setup: Setup,
    reduce: ComputePipeline,
    block_sums: ComputePipeline,
    downsweep: ComputePipeline,
    small: ComputePipeline,
    tuning: Tuning,
}

impl Scan {
    pub fn new(gpu: &Gpu, tuning: &Tuning) -> Result<Self> {
        let seg = Self::segment(tuning);
        let spec = if seg > 0 {
            [tuning.workgroup_size, seg]
        } else {
            [tuning.workgroup_size, tuning.items_per_invocation]
        };
        log::debug!(
            "scan on {}: {} — kernels {} + {}",
            gpu.info().name,
            tuning.describe(),
            Self::reduce_kernel(gpu, tuning).name,
            Self::downsweep_kernel(gpu, tuning).name
        );
        Ok(Self {
            setup: Setup::new(gpu)?,
            reduce: compute_pipeline(gpu, Self::reduce_kernel(gpu, tuning), 3, 4, &spec)?,
            block_sums: compute_pipeline(
                gpu,
                shaders::PRIMITIVES_SCAN_BLOCK_SUMS,
                2,
                0,
                &[tuning.workgroup_size],
            )?,
            downsweep: compute_pipeline(gpu, Self::downsweep_kernel(gpu, tuning), 4, 4, &spec)?,
            small: compute_pipeline(
                gpu,
                shaders::PRIMITIVES_SCAN_SMALL,
                2,
                size_of::<SmallPush>() as u32,
                &[tuning.workgroup_size],
            )?,
            tuning: *tuning,
        })
    }

    /// Whether the subgroup-row kernels are valid (see [`Tuning::subgroup_rows`]).
    fn rows(gpu: &Gpu, tuning: &Tuning) -> bool {
        let info = gpu.info();
        tuning.subgroup_rows
            && info.capabilities.subgroup_arithmetic
            && tuning.workgroup_size == info.limits.subgroup_size
            && tuning.items_per_invocation % 4 == 0
    }

    /// Items per invocation of the segment scan ([`Tuning::scan_segment`]), 0 where off.
    pub(crate) fn segment(tuning: &Tuning) -> u32 {
        if tuning.scan_segment % 4 == 0 {
            tuning.scan_segment
        } else {
            0
        }
    }

    /// Whether the segment kernels run their `wide64` variants: 64-bit accesses of
    /// eight items ([`Tuning::wide_accesses`]), for segments of a multiple of 8 items.
    pub(crate) fn wide(gpu: &Gpu, tuning: &Tuning) -> bool {
        tuning.wide_segments(gpu.info(), Self::segment(tuning))
    }

    /// Items per tile sum: per workgroup, or per invocation for the segment scan.
    fn tile(&self) -> u32 {
        match Self::segment(&self.tuning) {
            0 => self.tuning.tile(),
            seg => seg,
        }
    }

    /// Tile sums read as uvec4s where the runs allow (the tile is the same either way).
    fn reduce_kernel(gpu: &Gpu, tuning: &Tuning) -> crate::shaders::Kernel {
        if Self::wide(gpu, tuning) {
            shaders::PRIMITIVES_SCAN_SEG_REDUCE__WIDE64
        } else if Self::segment(tuning) > 0 {
            shaders::PRIMITIVES_SCAN_SEG_REDUCE
        } else if tuning.items_per_invocation % 4 == 0 {
            shaders::PRIMITIVES_SCAN_REDUCE__VEC4
        } else {
            shaders::PRIMITIVES_SCAN_REDUCE
        }
    }

    /// The subgroup-row kernel where it is valid, else per-invocation runs.
    fn downsweep_kernel(gpu: &Gpu, tuning: &Tuning) -> crate::shaders::Kernel {
        if Self::wide(gpu, tuning) {
            shaders::PRIMITIVES_SCAN_SEG__WIDE64
        } else if Self::segment(tuning) > 0 {
            shaders::PRIMITIVES_SCAN_SEG
        } else if Self::rows(gpu, tuning) {
            shaders::PRIMITIVES_SCAN_ROWS
        } else if tuning.items_per_invocation % 4 == 0 {
            shaders::PRIMITIVES_SCAN_DOWNSWEEP__VEC4
        } else {
            shaders::PRIMITIVES_SCAN_DOWNSWEEP
        }
    }

    fn tiles(&self, max_n: u32) -> u64 {
        (max_n as u64).div_ceil(self.tile() as u64).max(1)
    }

    /// Scratch bytes for scans of up to `max_n` items.
    pub fn scratch_bytes(&self, max_n: u32) -> u64 {
        HEADER_BYTES + region(self.tiles(max_n) * 4)
    }

    /// Records `output[i] = scan(input)[i]` for `i < n`. `input` and `output` may be the
    /// same buffer. Inputs must be visible to compute reads; ends with a barrier.
    pub fn record(
        &self,
        rec: &mut Recorder,
        n: u32,
        input: BufferSlice<'_>,
        output: BufferSlice<'_>,
        kind: ScanKind,
        scratch: &Buffer,
    ) -> Result<()> {
        self.record_count(rec, Count::Host(n), input, output, kind, false, scratch, 0)
    }

    /// As [`Scan::record`], with n read on the GPU from the u32 at byte `count_offset` of
    /// `count` (clamped to `max_n`, the capacity the scratch was sized for).
    #[allow(clippy::too_many_arguments)]
    pub fn record_indirect(
        &self,
        rec: &mut Recorder,
        count: &Buffer,
        count_offset: u64,
        max_n: u32,
        input: BufferSlice<'_>,
        output: BufferSlice<'_>,
        kind: ScanKind,
        scratch: &Buffer,
    ) -> Result<()> {
        let count = Count::Gpu {
            buffer: count,
            offset: count_offset,
            max: max_n,
        };
        self.record_count(rec, count, input, output, kind, false, scratch, 0)
    }

    /// Scans with n from `count`; `predicate` scans `(x != 0) as u32` instead of `x`.
    /// The scratch region starts at byte `base` of `scratch`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record_count(
        &self,
        rec: &mut Recorder,
        count: Count<'_>,
        input: BufferSlice<'_>,
        output: BufferSlice<'_>,
        kind: ScanKind,
        predicate: bool,
        scratch: &Buffer,
        base: u64,
    ) -> Result<()> {
        if let Count::Host(n) = count {
            if n <= SMALL_SCAN_MAX {
                return self.record_small(rec, n, input, output, kind, predicate);
            }
        }
        self.record_setup(rec, count, 1, scratch, base, None)?;
        self.record_passes(
            rec,
            input,
            output,
            kind,
            predicate,
            count.capacity(),
            scratch,
            base,
        )
    }

    /// The one-dispatch scan of `n` ≤ [`SMALL_SCAN_MAX`] items; ends with a barrier.
    fn record_small(
        &self,
        rec: &mut Recorder,
        n: u32,
        input: BufferSlice<'_>,
        output: BufferSlice<'_>,
        kind: ScanKind,
        predicate: bool,
    ) -> Result<()> {
        debug_assert!(n <= SMALL_SCAN_MAX);
        let inclusive = if kind == ScanKind::Inclusive { 2 } else { 0 };
        rec.dispatch(
            &self.small,
            &[input, output],
            &SmallPush {
                n,
                flags: predicate as u32 | inclusive,
            },
            [1, 1, 1],
        )?;
        rec.barrier();
        Ok(())
    }

    /// Writes the scan's header (n = count × `mul`), and 0 to `zero` where given (a
    /// caller's output count, so that n = 0 leaves it right).
    pub(crate) fn record_setup(
        &self,
        rec: &mut Recorder,
        count: Count<'_>,
        mul: u32,
        scratch: &Buffer,
        base: u64,
        zero: Option<BufferSlice<'_>>,
    ) -> Result<()> {
        let cap = count
            .capacity()
            .saturating_mul(if matches!(count, Count::Host(_)) {
                1
            } else {
                mul
            });
        check_scratch("scan", scratch, base, self.scratch_bytes(cap))?;
        let count = match count {
            Count::Gpu {
                buffer,
                offset,
                max,
            } => Count::Gpu {
                buffer,
                offset,
                max: max.saturating_mul(mul),
            },
            c => c,
        };
        self.setup.record(
            rec,
            count,
            mul,
            scratch.slice(base, HEADER_BYTES),
            // Kind 0 counts the tile sums; kind 1 the segment scan's workgroups.
            [self.tile(), self.tile() * self.tuning.workgroup_size, 0, 0],
            zero,
        )
    }

    /// The scan's first two passes (header at `base` already written): the exclusive
    /// offset of every tile's first item — of every invocation's segment with
    /// [`Tuning::scan_segment`] — for a caller that walks the tiles itself (the segment
    /// compaction). Ends with a barrier.
    pub(crate) fn record_tile_offsets<'s>(
        &self,
        rec: &mut Recorder,
        input: BufferSlice<'_>,
        predicate: bool,
        max_n: u32,
        scratch: &'s Buffer,
        base: u64,
    ) -> Result<TileOffsets<'s>> {
        let header = scratch.slice(base, HEADER_BYTES);
        let sums = scratch.slice(base + HEADER_BYTES, region(self.tiles(max_n) * 4));
        let args = base
            + args_offset(if Self::segment(&self.tuning) > 0 {
                1
            } else {
                0
            });
        rec.dispatch_indirect(
            &self.reduce,
            &[header, input, sums],
            &FlagsPush {
                flags: predicate as u32,
            },
            scratch,
            args,
        )?;
        rec.barrier();
        rec.dispatch(&self.block_sums, &[header, sums], &(), [1, 1, 1])?;
        rec.barrier();
        Ok(TileOffsets { header, sums, args })
    }

    /// The three scan passes, reading n from the header at `base` (already written).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record_passes(
        &self,
        rec: &mut Recorder,
        input: BufferSlice<'_>,
        output: BufferSlice<'_>,
        kind: ScanKind,
        predicate: bool,
        max_n: u32,
        scratch: &Buffer,
        base: u64,
    ) -> Result<()> {
        let TileOffsets { header, sums, args } =
            self.record_tile_offsets(rec, input, predicate, max_n, scratch, base)?;
        let pred = predicate as u32;
        let inclusive = if kind == ScanKind::Inclusive { 2 } else { 0 };
        rec.dispatch_indirect(
            &self.downsweep,
            &[header, input, sums, output],
            &FlagsPush {
                flags: pred | inclusive,
            },
            scratch,
            args,
        )?;
        rec.barrier();
        Ok(())
    }
}

/// What [`Scan::record_tile_offsets`] leaves for the pass that follows it.
pub(crate) struct TileOffsets<'s> {
    /// The scan's header: n, and the tile / segment counts and dispatch arguments.
    pub header: BufferSlice<'s>,
    /// Exclusive offset of each tile (segment).
    pub sums: BufferSlice<'s>,
    /// Byte offset in the scratch of the indirect arguments that cover the tiles.
    pub args: u64,
}
