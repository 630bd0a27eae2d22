//! Stable LSD radix sort of u32 keys carrying u32 values, over an optional bit range.
//!
//! Per pass of `radix_bits` bits: (1) per-tile digit histograms, each invocation
//! counting its own contiguous keys into its own shared-memory column; (2) one
//! exclusive [`Scan`] of the digit-major histogram (`hist[digit * tiles + tile]`) gives
//! every (digit, tile) its global offset; (3) a stable scatter in which each tile
//! recounts, turns per-invocation counts into offsets, and writes its keys in order. No
//! workgroup ever waits on another (no forward-progress assumption). Passes ping-pong
//! between the caller's buffers and the scratch pair; after an odd number of passes a
//! copy brings the result home, so the sorted pairs always end in the caller's buffers.
//!
//! The multisplit variant ([`Tuning::sort_multisplit`], GPUs) counts each tile's digits
//! with shared atomics and, in the scatter, ranks the keys of each subgroup with ballots
//! over the digit bits, sorts the tile in shared memory and writes every digit's run
//! coalesced (`sort_ms_scatter.comp` has the details). Its 8-bit digits take 4 passes
//! for 32-bit keys.
//!
//! The segment variant ([`Tuning::sort_segments`], CPU devices) has no barrier at all:
//! every invocation's keys are one segment with its own histogram, written digit-major
//! across all segments (`hist[digit * segments + segment]`), so the scan gives every
//! (digit, segment) its offset directly and each invocation scatters its segment alone.
//! With [`Tuning::sort_pairs`] key-value sorts run through interleaved (key, value)
//! pairs in the scratch: the first pass reads the caller's buffers and writes pairs,
//! middle passes go from pairs to pairs (two pair buffers, alternating), and the last
//! pass writes the caller's buffers again — no unpack or copy for any pass count above
//! one (a single pass ends with an unpack kernel). The scatter is compiled once for each
//! of those three pass kinds, so that none of them branches on the kind. With
//! [`Tuning::wide_accesses`] the segment kernels read keys eight at a time (or pairs four
//! at a time) as `u64vec4`s and store each pair as one 64-bit word, and key-value sorts
//! keep pairs through their last pass too and end with a streaming unpack.

use super::tuning::multisplit_supported;
use super::{
    args_offset, check_scratch, region, Count, Scan, ScanKind, Setup, Tuning, HEADER_BYTES,
};
use crate::shaders::{self, Kernel};
use crate::vk::{
    compute_pipeline, compute_pipeline_full_subgroups, Buffer, BufferSlice, ComputePipeline, Gpu,
    MemoryKind, PhysicalDeviceInfo, Recorder, Result, VkError,
};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PassPush {
    shift: u32,
    bits: u32,
    flags: u32,
}

/// The ping-pong pair and the misc scratch of one sort.
pub struct SortScratch {
    /// `max_n` u32 keys; with [`Tuning::sort_pairs`] `2 * max_n` words, which
    /// key-value sorts use as interleaved (key, value) pairs.
    pub keys: Buffer,
    /// `max_n` u32 values; with [`Tuning::sort_pairs`] `2 * max_n` words, the second
    /// buffer of interleaved pairs.
    pub values: Buffer,
    /// Header, histograms and the histogram scan's scratch: [`RadixSort::scratch_bytes`].
    pub misc: Buffer,
}

/// The scatter per kind of key-value segment pass.
struct PairScatters {
    /// The caller's arrays to pairs.
    first: ComputePipeline,
    /// Pairs to pairs.
    middle: ComputePipeline,
    /// Pairs to the caller's arrays. Absent with 64-bit accesses: key-value sorts then
    /// keep pairs through their last pass and end with the streaming unpack
    /// ([`RadixSort::splits_last`]), since two scattered 32-bit stores per key cost more
    /// on lavapipe than one scattered 64-bit store plus the split. 4M pairs, medians of
    /// 40 runs alternating the two in one process, three runs (2026-11-24): 52.1 / 50.9
    /// / 51.6 ms against 54.2 / 54.3 / 55.3 ms.
    last: Option<ComputePipeline>,
}

impl PairScatters {
    /// The three scatters, or with 64-bit accesses (`wide`) the first two.
    fn new(gpu: &Gpu, wide: bool, spec: &[u32; 3]) -> Result<Self> {
        let kind = |k| compute_pipeline(gpu, k, 6, 12, spec);
        Ok(if wide {
            Self {
                first: kind(shaders::PRIMITIVES_SORT_SEG_SCATTER__FIRST64)?,
                middle: kind(shaders::PRIMITIVES_SORT_SEG_SCATTER__MIDDLE64)?,
                last: None,
            }
        } else {
            Self {
                first: kind(shaders::PRIMITIVES_SORT_SEG_SCATTER__FIRST)?,
                middle: kind(shaders::PRIMITIVES_SORT_SEG_SCATTER__MIDDLE)?,
                last: Some(kind(shaders::PRIMITIVES_SORT_SEG_SCATTER__LAST)?),
            }
        })
    }
}

pub struct RadixSort {
    setup: Setup,
    histogram: ComputePipeline,
    scatter: ComputePipeline,
    /// With interleaved pairs: the scatter compiled for each kind of key-value pass
    /// (first: arrays to pairs, middle: pairs to pairs, last: pairs to arrays), so the
    /// branches on the pass kind fold away. On lavapipe that took a 4M-pair sort from
    /// 70.1 / 69.9 / 68.7 / 70.2 to 67.3 / 67.9 / 64.7 / 66.2 ms (tuning sweep, minima
    /// of 4 interleaved rounds, four sweeps alternating the two).
    pair_scatters: Option<PairScatters>,
    copy: ComputePipeline,
    /// Pairs back to keys and values: after a single pass, and at the end of every
    /// key-value sort that [`RadixSort::splits_last`].
    unpack: Option<ComputePipeline>,
    scan: Scan,
    tuning: Tuning,
    rows: bool,
    /// Barrier-free segments ([`Tuning::sort_segments`]): histograms per invocation.
    segments: bool,
    /// Multisplit tiles ([`Tuning::sort_multisplit`]).
    multisplit: bool,
    /// Interleaved pairs in the scratch ([`Tuning::sort_pairs`], segments only).
    pairs: bool,
}

impl RadixSort {
    pub fn new(gpu: &Gpu, tuning: &Tuning) -> Result<Self> {
        let spec = [
            tuning.sort_workgroup_size,
            tuning.sort_keys_per_invocation,
            tuning.radix_bits,
        ];
        let info = gpu.info();
        check_tuning_fits(info, tuning)?;
        let multisplit = tuning.sort_multisplit;
        // The row variant needs the workgroup to be exactly one subgroup.
        let rows = !multisplit
            && tuning.sort_rows
            && tuning.sort_workgroup_size == info.limits.subgroup_size;
        let segments = !multisplit
            && !rows
            && tuning.sort_segments
            && tuning.sort_keys_per_invocation % 4 == 0;
        let wide = segments && tuning.wide_segments(info, tuning.sort_keys_per_invocation);
        let (histogram, scatter) = pass_kernels(tuning, multisplit, rows, segments, wide);
        log::info!(
            "radix sort on {}: {} — kernels {} + {}",
            gpu.info().name,
            tuning.describe(),
            histogram.name,
            scatter.name
        );
        // Segment and multisplit kernels bind no per-invocation count table.
        let tableless = segments || multisplit;
        let scatter = if multisplit {
            let max_subgroups = tuning.sort_max_subgroups(info);
            compute_pipeline_full_subgroups(
                gpu,
                scatter,
                6,
                12,
                &[spec[0], spec[1], spec[2], max_subgroups],
            )?
        } else {
            compute_pipeline(gpu, scatter, if segments { 6 } else { 7 }, 12, &spec)?
        };
        let pairs = segments && tuning.sort_pairs;
        Ok(Self {
            setup: Setup::new(gpu)?,
            histogram: compute_pipeline(gpu, histogram, if tableless { 3 } else { 4 }, 12, &spec)?,
            scatter,
            pair_scatters: pairs
                .then(|| PairScatters::new(gpu, wide, &spec))
                .transpose()?,
            rows,
            segments,
            multisplit,
            pairs,
            unpack: pairs
                .then(|| unpack_pipeline(gpu, wide, &spec))
                .transpose()?,
            copy: compute_pipeline(
                gpu,
                shaders::PRIMITIVES_COPY_PAIRS,
                5,
                4,
                &[tuning.workgroup_size, tuning.items_per_invocation],
            )?,
            scan: Scan::new(gpu, tuning)?,
            tuning: *tuning,
        })
    }

    pub fn tuning(&self) -> &Tuning {
        &self.tuning
    }

    /// Whether key-value sorts keep pairs through their last pass and end with the
    /// unpack kernel (no last-pass scatter: see [`PairScatters::last`]).
    fn splits_last(&self) -> bool {
        self.pair_scatters
            .as_ref()
            .is_some_and(|k| k.last.is_none())
    }

    fn radix(&self) -> u32 {
        1 << self.tuning.radix_bits
    }

    fn tiles(&self, max_n: u32) -> u64 {
        (max_n as u64)
            .div_ceil(self.tuning.sort_tile() as u64)
            .max(1)
    }

    /// Histogram rows per tile: one per invocation for segments, else one.
    fn hist_rows(&self) -> u32 {
        if self.segments {
            self.tuning.sort_workgroup_size
        } else {
            1
        }
    }

    fn hist_len(&self, max_n: u32) -> u32 {
        (self.tiles(max_n) * self.radix() as u64 * self.hist_rows() as u64) as u32
    }

    /// Whether the histogram pass stores its per-invocation counts for the scatter
    /// (instead of the scatter counting again): where that table (radix × workgroup
    /// words per tile) is at most a quarter of the tile's keys.
    fn stores_lane_counts(&self) -> bool {
        !self.rows && !self.tableless() && self.radix() * 4 <= self.tuning.sort_keys_per_invocation
    }

    /// Whether the kernels bind no per-invocation count table (segments, multisplit).
    fn tableless(&self) -> bool {
        self.segments || self.multisplit
    }

    fn lane_counts_len(&self, max_n: u32) -> u64 {
        if self.stores_lane_counts() {
            self.tiles(max_n) * self.radix() as u64 * self.tuning.sort_workgroup_size as u64
        } else {
            0
        }
    }

    /// (histogram, per-invocation counts, inner scan) offsets inside the misc scratch.
    fn layout(&self, max_n: u32) -> (u64, u64, u64) {
        let hist = HEADER_BYTES;
        let lanes = hist + region(self.hist_len(max_n) as u64 * 4);
        let scan = lanes + region(self.lane_counts_len(max_n) * 4);
        (hist, lanes, scan)
    }

    /// Bytes of the misc scratch for up to `max_n` keys (the ping-pong pair needs
    /// `4 * max_n` bytes each on top).
    pub fn scratch_bytes(&self, max_n: u32) -> u64 {
        let (_, _, scan) = self.layout(max_n);
        scan + self.scan.scratch_bytes(self.hist_len(max_n))
    }

    /// Allocates the scratch for sorts of up to `max_n` keys.
    pub fn alloc_scratch(&self, gpu: &Gpu, max_n: u32) -> Result<SortScratch> {
        let bytes = max_n as u64 * 4;
        let (keys, values) = if self.pairs {
            (2 * bytes, 2 * bytes)
        } else {
            (bytes, bytes)
        };
        Ok(SortScratch {
            keys: gpu.create_buffer("sort-scratch-keys", keys, MemoryKind::Device)?,
            values: gpu.create_buffer("sort-scratch-values", values, MemoryKind::Device)?,
            misc: gpu.create_buffer(
                "sort-scratch-misc",
                self.scratch_bytes(max_n),
                MemoryKind::Device,
            )?,
        })
    }

    /// Number of passes for the bit range `[begin_bit, end_bit)`.
    pub fn passes(&self, begin_bit: u32, end_bit: u32) -> u32 {
        end_bit
            .saturating_sub(begin_bit)
            .div_ceil(self.tuning.radix_bits)
    }

    /// Sorts the first `n` pairs of (`keys`, `values`) in place by the bits
    /// `[begin_bit, end_bit)` of the keys (0..32 for whole keys), stably: pairs whose
    /// keys agree on those bits keep their order. `values: None` sorts keys alone.
    /// Inputs must be visible to compute reads; ends with a barrier.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        n: u32,
        keys: BufferSlice<'_>,
        values: Option<BufferSlice<'_>>,
        bits: std::ops::Range<u32>,
        scratch: &SortScratch,
    ) -> Result<()> {
        self.record_count(rec, Count::Host(n), keys, values, bits, scratch)
    }

    /// As [`RadixSort::record`], with n read on the GPU from the u32 at byte
    /// `count_offset` of `count`, clamped to `max_n` (the capacity of `scratch`).
    #[allow(clippy::too_many_arguments)]
    pub fn record_indirect(
        &self,
        rec: &mut Recorder,
        count: &Buffer,
        count_offset: u64,
        max_n: u32,
        keys: BufferSlice<'_>,
        values: Option<BufferSlice<'_>>,
        bits: std::ops::Range<u32>,
        scratch: &SortScratch,
    ) -> Result<()> {
        let count = Count::Gpu {
            buffer: count,
            offset: count_offset,
            max: max_n,
        };
        self.record_count(rec, count, keys, values, bits, scratch)
    }

    fn record_count(
        &self,
        rec: &mut Recorder,
        count: Count<'_>,
        keys: BufferSlice<'_>,
        values: Option<BufferSlice<'_>>,
        bits: std::ops::Range<u32>,
        scratch: &SortScratch,
    ) -> Result<()> {
        if bits.start > bits.end || bits.end > 32 {
            return Err(VkError::Usage(format!(
                "radix sort: bad bit range {bits:?}"
            )));
        }
        let cap = count.capacity();
        let passes = self.passes(bits.start, bits.end);
        if passes == 0 {
            rec.barrier();
            return Ok(());
        }
        self.check_sort_scratch(scratch, cap, passes, values.is_some())?;
        let misc = &scratch.misc;
        let (hist_off, lanes_off, scan_off) = self.layout(cap);
        let plan = PassPlan {
            misc,
            header: misc.slice(0, HEADER_BYTES),
            hist: misc.slice(hist_off, region(self.hist_len(cap) as u64 * 4)),
            lanes: misc.slice(lanes_off, region(self.lane_counts_len(cap) * 4)),
            scan_off,
            cap,
            passes,
            bits,
        };
        self.record_setup(rec, count, &plan)?;
        match values {
            // Key-value segment sorts ping-pong through interleaved pairs in scratch.keys.
            Some(vals) if self.pairs => self.record_pair_passes(rec, &plan, keys, vals, scratch),
            _ => self.record_array_passes(rec, &plan, count, keys, values, scratch),
        }
    }

    /// Checks that `scratch` holds what a sort of up to `cap` keys in `passes` passes
    /// needs (with values or not).
    fn check_sort_scratch(
        &self,
        scratch: &SortScratch,
        cap: u32,
        passes: u32,
        with_values: bool,
    ) -> Result<()> {
        check_scratch("radix sort", &scratch.misc, 0, self.scratch_bytes(cap))?;
        if self.pairs {
            let words = if with_values { 2 } else { 1 };
            check_scratch("radix sort", &scratch.keys, 0, cap as u64 * 4 * words)?;
            if with_values && (passes > 2 || (self.splits_last() && passes > 1)) {
                check_scratch("radix sort", &scratch.values, 0, cap as u64 * 8)?;
            }
        } else {
            for b in [&scratch.keys, &scratch.values] {
                check_scratch("radix sort", b, 0, cap as u64 * 4)?;
            }
        }
        Ok(())
    }

    /// The sort's header (dispatch sizes from the count) and the histogram scan's setup.
    fn record_setup(&self, rec: &mut Recorder, count: Count<'_>, plan: &PassPlan) -> Result<()> {
        self.setup.record(
            rec,
            count,
            1,
            plan.header,
            [self.tuning.tile(), self.tuning.sort_tile(), 0, 0],
            None,
        )?;
        // The histogram scan's n = tiles × radix, read from this header on the GPU.
        let tiles_count = Count::Gpu {
            buffer: plan.misc,
            offset: 4 * 2, // HDR_GROUPS + 1: the tile count of dispatch kind 1
            max: self.tiles(plan.cap) as u32,
        };
        self.scan.record_setup(
            rec,
            tiles_count,
            self.radix() * self.hist_rows(),
            plan.misc,
            plan.scan_off,
            None,
        )
    }

    /// One pass's histogram and its exclusive scan (in place).
    fn record_histogram(
        &self,
        rec: &mut Recorder,
        plan: &PassPlan,
        bindings: &[BufferSlice<'_>],
        push: &PassPush,
    ) -> Result<()> {
        rec.dispatch_indirect(&self.histogram, bindings, push, plan.misc, args_offset(1))?;
        rec.barrier();
        self.scan.record_passes(
            rec,
            plan.hist,
            plan.hist,
            ScanKind::Exclusive,
            false,
            self.hist_len(plan.cap),
            plan.misc,
            plan.scan_off,
        )
    }

    /// The push constants of pass `pass`.
    fn pass_push(&self, plan: &PassPlan, pass: u32, flags: u32) -> PassPush {
        let shift = plan.bits.start + pass * self.tuning.radix_bits;
        PassPush {
            shift,
            bits: (plan.bits.end - shift).min(self.tuning.radix_bits),
            flags,
        }
    }

    /// Key-value passes through interleaved pairs: the first pass reads the caller's
    /// arrays, the middle ones go pairs to pairs, the last writes the caller's arrays
    /// (or pairs that an unpack splits, after one pass or where the sort splits last).
    fn record_pair_passes(
        &self,
        rec: &mut Recorder,
        plan: &PassPlan,
        keys: BufferSlice<'_>,
        vals: BufferSlice<'_>,
        scratch: &SortScratch,
    ) -> Result<()> {
        let pair_buffers = [
            BufferSlice::from(&scratch.keys),
            BufferSlice::from(&scratch.values),
        ];
        let passes = plan.passes;
        for pass in 0..passes {
            // The first pass reads the caller's buffers, the last (if not also the
            // first, and unless the sort splits its pairs at the end) writes them;
            // everything in between is pairs to pairs.
            let pairs_in = pass > 0;
            let to_pairs = pass == 0 || pass + 1 < passes || self.splits_last();
            let flags = 1 | if pairs_in { 4 } else { 0 } | if to_pairs { 8 } else { 0 };
            let push = self.pass_push(plan, pass, flags);
            let (ki, vi) = if pairs_in {
                let p = pair_buffers[(pass as usize - 1) % 2];
                (p, p)
            } else {
                (keys, vals)
            };
            let (ko, vo) = if to_pairs {
                let p = pair_buffers[pass as usize % 2];
                (p, p)
            } else {
                (keys, vals)
            };
            self.record_histogram(rec, plan, &[plan.header, ki, plan.hist], &push)?;
            let scatter = match &self.pair_scatters {
                Some(kinds) if !pairs_in => &kinds.first,
                Some(kinds) if to_pairs => &kinds.middle,
                Some(PairScatters {
                    last: Some(last), ..
                }) => last,
                _ => &self.scatter,
            };
            rec.dispatch_indirect(
                scatter,
                &[plan.header, ki, vi, plan.hist, ko, vo],
                &push,
                plan.misc,
                args_offset(1),
            )?;
            rec.barrier();
        }
        // The result is still in pairs after a single pass, or after every pass
        // when the sort splits its pairs at the end: split them into the caller's arrays.
        if let (true, Some(unpack)) = (passes == 1 || self.splits_last(), &self.unpack) {
            let p = pair_buffers[(passes as usize - 1) % 2];
            rec.dispatch_indirect(
                unpack,
                &[plan.header, p, keys, vals],
                &(),
                plan.misc,
                args_offset(1),
            )?;
            rec.barrier();
        }
        Ok(())
    }

    /// Passes between the caller's arrays and the scratch pair, keys (and values) as
    /// separate arrays; an odd number of passes copies the result back.
    fn record_array_passes(
        &self,
        rec: &mut Recorder,
        plan: &PassPlan,
        count: Count<'_>,
        keys: BufferSlice<'_>,
        values: Option<BufferSlice<'_>>,
        scratch: &SortScratch,
    ) -> Result<()> {
        let with_values = values.is_some() as u32;
        let stored = if self.stores_lane_counts() { 2 } else { 0 };
        let tmp_keys = BufferSlice::from(&scratch.keys);
        let tmp_vals = BufferSlice::from(&scratch.values);
        let vals = values.unwrap_or(keys);
        let tmp_v = if values.is_some() { tmp_vals } else { tmp_keys };
        let mut src = (keys, vals);
        let mut dst = (tmp_keys, tmp_v);
        let used = if self.tableless() { 0 } else { 1 };
        for pass in 0..plan.passes {
            let push = self.pass_push(plan, pass, with_values | stored);
            let count_bindings = [plan.header, src.0, plan.hist, plan.lanes];
            self.record_histogram(rec, plan, &count_bindings[..3 + used], &push)?;
            let scatter_bindings = [
                plan.header,
                src.0,
                src.1,
                plan.hist,
                dst.0,
                dst.1,
                plan.lanes,
            ];
            rec.dispatch_indirect(
                &self.scatter,
                &scatter_bindings[..6 + used],
                &push,
                plan.misc,
                args_offset(1),
            )?;
            rec.barrier();
            std::mem::swap(&mut src, &mut dst);
        }
        if plan.passes % 2 == 1 {
            // An odd number of passes left the result in the scratch pair.
            self.record_copy_back(rec, plan, count, src, dst, values.is_some())?;
        }
        Ok(())
    }

    /// Copies the sorted keys (and values) from `src` to `dst`.
    fn record_copy_back(
        &self,
        rec: &mut Recorder,
        plan: &PassPlan,
        count: Count<'_>,
        src: (BufferSlice<'_>, BufferSlice<'_>),
        dst: (BufferSlice<'_>, BufferSlice<'_>),
        with_values: bool,
    ) -> Result<()> {
        match count {
            // n known here: a transfer copy (memcpy speed on CPU devices).
            Count::Host(n) => {
                let bytes = n as u64 * 4;
                if bytes > 0 {
                    rec.copy(
                        src.0.buffer,
                        src.0.offset,
                        dst.0.buffer,
                        dst.0.offset,
                        bytes,
                    );
                    if with_values {
                        rec.copy(
                            src.1.buffer,
                            src.1.offset,
                            dst.1.buffer,
                            dst.1.offset,
                            bytes,
                        );
                    }
                }
            }
            Count::Gpu { .. } => rec.dispatch_indirect(
                &self.copy,
                &[plan.header, src.0, src.1, dst.0, dst.1],
                &(with_values as u32),
                plan.misc,
                args_offset(0),
            )?,
        }
        rec.barrier();
        Ok(())
    }
}

/// Where one sort's passes find their scratch regions, and how many they make.
struct PassPlan<'a> {
    misc: &'a Buffer,
    header: BufferSlice<'a>,
    hist: BufferSlice<'a>,
    lanes: BufferSlice<'a>,
    scan_off: u64,
    cap: u32,
    passes: u32,
    bits: std::ops::Range<u32>,
}

/// Fails where `tuning` asks more shared memory than the device has, or the multisplit
/// variant where the device cannot run it.
fn check_tuning_fits(info: &PhysicalDeviceInfo, tuning: &Tuning) -> Result<()> {
    let shared = info.limits.max_compute_shared_memory_size as u64;
    if tuning.sort_shared_bytes(info) > shared {
        return Err(VkError::Usage(format!(
            "radix sort tuning needs {} bytes of shared memory; the device has {shared}",
            tuning.sort_shared_bytes(info)
        )));
    }
    if tuning.sort_multisplit
        && (!multisplit_supported(info, tuning.sort_workgroup_size) || tuning.radix_bits > 8)
    {
        return Err(VkError::Usage(format!(
            "radix sort: the multisplit variant ({}) cannot run on '{}' (it needs subgroup \
             ballot, shuffle and arithmetic, full subgroups, a workgroup that is a multiple \
             of the largest subgroup size {}, and digits of at most 8 bits)",
            tuning.describe(),
            info.name,
            info.limits.max_subgroup_size
        )));
    }
    Ok(())
}

/// The histogram and scatter kernels of a pass in the variant chosen.
fn pass_kernels(
    tuning: &Tuning,
    multisplit: bool,
    rows: bool,
    segments: bool,
    wide: bool,
) -> (Kernel, Kernel) {
    if multisplit {
        (
            shaders::PRIMITIVES_SORT_MS_COUNT,
            shaders::PRIMITIVES_SORT_MS_SCATTER,
        )
    } else if segments && wide {
        (
            shaders::PRIMITIVES_SORT_SEG_COUNT__WIDE64,
            shaders::PRIMITIVES_SORT_SEG_SCATTER,
        )
    } else if segments {
        (
            shaders::PRIMITIVES_SORT_SEG_COUNT,
            shaders::PRIMITIVES_SORT_SEG_SCATTER,
        )
    } else if rows {
        (
            shaders::PRIMITIVES_SORT_HISTOGRAM__ROWS,
            shaders::PRIMITIVES_SORT_SCATTER_ROWS,
        )
    } else if tuning.sort_keys_per_invocation % 4 == 0 {
        // Runs read as uvec4s (a quarter of the per-lane accesses).
        (
            shaders::PRIMITIVES_SORT_HISTOGRAM__VEC4,
            shaders::PRIMITIVES_SORT_SCATTER__VEC4,
        )
    } else {
        (
            shaders::PRIMITIVES_SORT_HISTOGRAM,
            shaders::PRIMITIVES_SORT_SCATTER,
        )
    }
}

/// Pairs back to keys and values, from 64-bit words where the segments are `wide`.
fn unpack_pipeline(gpu: &Gpu, wide: bool, spec: &[u32; 3]) -> Result<ComputePipeline> {
    compute_pipeline(
        gpu,
        if wide {
            shaders::PRIMITIVES_SORT_UNPACK__WIDE64
        } else {
            shaders::PRIMITIVES_SORT_UNPACK
        },
        4,
        0,
        &spec[..2],
    )
}
