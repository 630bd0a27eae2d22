//! Reduce-by-key over sorted keys (runs of equal keys): sum of u32 values, arg-min of
//! (f32 t, u32 id) pairs, and run-length encoding (unique keys and counts).
//!
//! Passes: heads (`key[i] != key[i-1]`) → inclusive [`Scan`] → run ids; at each head the
//! unique key and the identity are written and the last item writes the run count; then
//! each invocation walks a contiguous run of items, reduces locally and issues one
//! atomic per run piece (integer atomics: the result does not depend on their order).
//!
//! On CPU devices ([`Tuning::scan_segment`]) a barrier-free segment variant replaces
//! all of that: every invocation counts the run heads in its own segment of contiguous
//! keys, one small exclusive scan of those counts numbers the runs, and each invocation
//! then reduces every run whose head lies in its segment, to the run's end even past the
//! segment, so that no run is split: no atomics, one pass for the arg-min, no per-item
//! run-id array, and half or fewer of the general path's key reads (lavapipe pays per
//! accessed word).
//!
//! Arg-min: the smallest t by IEEE total order (`f32::total_cmp`, so -0 < +0; NaNs are
//! ordered by their bits, not recommended), ties broken by the smaller id — the per-ray
//! closest hit of PDACRT Algorithm 3.

use super::{
    args_offset, check_scratch, region, Count, Scan, ScanKind, Setup, Tuning, HEADER_BYTES,
};
use crate::shaders;
use crate::vk::{compute_pipeline, Buffer, BufferSlice, ComputePipeline, Gpu, Recorder, Result};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ModePush {
    mode: u32,
}

/// What to reduce.
#[derive(Clone, Copy, Debug)]
pub enum Reduction<'a> {
    /// `out_a[s]` = wrapping sum of the run's u32 values.
    Sum { values: BufferSlice<'a> },
    /// `out_a[s]` = number of items in the run (run-length encoding).
    Count,
    /// `out_a[s]` = smallest f32 `t` of the run, `out_b[s]` = its id.
    ArgMin {
        t: BufferSlice<'a>,
        ids: BufferSlice<'a>,
    },
}

/// The outputs: unique keys, one or two value arrays (room for n runs each) and the
/// number of runs (one u32, readable on the GPU and the host).
#[derive(Clone, Copy, Debug)]
pub struct RunOutputs<'a> {
    pub keys: BufferSlice<'a>,
    pub a: BufferSlice<'a>,
    /// Only written by arg-min (ids); ignored otherwise.
    pub b: Option<BufferSlice<'a>>,
    pub count: BufferSlice<'a>,
}

/// The segment variant's kernels.
struct SegmentKernels {
    /// Items per segment (one segment per invocation).
    items: u32,
    heads: ComputePipeline,
    /// Sum, count, arg-min.
    reduce: [ComputePipeline; 3],
}

pub struct ReduceByKey {
    segments: Option<SegmentKernels>,
    setup: Setup,
    flags: ComputePipeline,
    init: ComputePipeline,
    reduce: ComputePipeline,
    finish: ComputePipeline,
    scan: Scan,
    tuning: Tuning,
}

impl ReduceByKey {
    pub fn new(gpu: &Gpu, tuning: &Tuning) -> Result<Self> {
        let spec = [tuning.workgroup_size, tuning.items_per_invocation];
        let segments = match Scan::segment(tuning) {
            0 => None,
            items => {
                let spec = [tuning.workgroup_size, items];
                let reduce = |k| compute_pipeline(gpu, k, 9, 0, &spec);
                Some(SegmentKernels {
                    items,
                    heads: compute_pipeline(
                        gpu,
                        if Scan::wide(gpu, tuning) {
                            shaders::PRIMITIVES_RBK_SEG_HEADS__WIDE64
                        } else {
                            shaders::PRIMITIVES_RBK_SEG_HEADS
                        },
                        3,
                        0,
                        &spec,
                    )?,
                    reduce: [
                        reduce(shaders::PRIMITIVES_RBK_SEG_REDUCE__SUM)?,
                        reduce(shaders::PRIMITIVES_RBK_SEG_REDUCE__COUNT)?,
                        reduce(shaders::PRIMITIVES_RBK_SEG_REDUCE__ARGMIN)?,
                    ],
                })
            }
        };
        Ok(Self {
            segments,
            setup: Setup::new(gpu)?,
            flags: compute_pipeline(gpu, shaders::PRIMITIVES_RBK_FLAGS, 3, 0, &spec)?,
            init: compute_pipeline(gpu, shaders::PRIMITIVES_RBK_INIT, 7, 4, &spec)?,
            reduce: compute_pipeline(gpu, shaders::PRIMITIVES_RBK_REDUCE, 6, 4, &spec)?,
            finish: compute_pipeline(gpu, shaders::PRIMITIVES_RBK_FINISH, 4, 0, &spec)?,
            scan: Scan::new(gpu, tuning)?,
            tuning: *tuning,
        })
    }

    /// Words of the per-item run ids (general path) or the per-segment head counts
    /// (segment variant) for up to `max_n` items.
    fn ids_len(&self, max_n: u32) -> u32 {
        match &self.segments {
            Some(k) => max_n.div_ceil(k.items),
            None => max_n,
        }
    }

    fn layout(&self, max_n: u32) -> (u64, u64) {
        let seg = HEADER_BYTES;
        let scan = seg + region(self.ids_len(max_n) as u64 * 4);
        (seg, scan)
    }

    /// Scratch bytes for up to `max_n` items.
    pub fn scratch_bytes(&self, max_n: u32) -> u64 {
        self.layout(max_n).1 + self.scan.scratch_bytes(self.ids_len(max_n))
    }

    /// Reduces the runs of equal keys among the first `n` of `keys` (sorted, or at
    /// least grouped). Inputs must be visible to compute reads; ends with a barrier.
    pub fn record(
        &self,
        rec: &mut Recorder,
        n: u32,
        keys: BufferSlice<'_>,
        reduction: Reduction<'_>,
        out: RunOutputs<'_>,
        scratch: &Buffer,
    ) -> Result<()> {
        self.record_count(rec, Count::Host(n), keys, reduction, out, scratch)
    }

    /// As [`ReduceByKey::record`], with n read on the GPU from the u32 at byte
    /// `count_offset` of `count`, clamped to `max_n` (the capacity of `scratch`).
    #[allow(clippy::too_many_arguments)]
    pub fn record_indirect(
        &self,
        rec: &mut Recorder,
        count: &Buffer,
        count_offset: u64,
        max_n: u32,
        keys: BufferSlice<'_>,
        reduction: Reduction<'_>,
        out: RunOutputs<'_>,
        scratch: &Buffer,
    ) -> Result<()> {
        let count = Count::Gpu {
            buffer: count,
            offset: count_offset,
            max: max_n,
        };
        self.record_count(rec, count, keys, reduction, out, scratch)
    }

    fn record_count(
        &self,
        rec: &mut Recorder,
        count: Count<'_>,
        keys: BufferSlice<'_>,
        reduction: Reduction<'_>,
        out: RunOutputs<'_>,
        scratch: &Buffer,
    ) -> Result<()> {
        let cap = count.capacity();
        check_scratch("reduce-by-key", scratch, 0, self.scratch_bytes(cap))?;
        if let Reduction::ArgMin { .. } = reduction {
            if out.b.is_none() {
                return Err(crate::vk::VkError::Usage(
                    "reduce-by-key arg-min needs an id output (RunOutputs::b)".into(),
                ));
            }
        }
        if let Some(kernels) = &self.segments {
            return self.record_segments(rec, kernels, count, keys, reduction, out, scratch);
        }
        let (seg_off, scan_off) = self.layout(cap);
        let header = scratch.slice(0, HEADER_BYTES);
        let seg = scratch.slice(seg_off, region(cap as u64 * 4));
        let args = args_offset(0);
        self.setup.record(
            rec,
            count,
            1,
            header,
            [self.tuning.tile(), 0, 0, 0],
            Some(out.count),
        )?;
        rec.dispatch_indirect(&self.flags, &[header, keys, seg], &(), scratch, args)?;
        rec.barrier();
        self.scan.record_count(
            rec,
            count,
            seg,
            seg,
            ScanKind::Inclusive,
            false,
            scratch,
            scan_off,
        )?;
        let argmin = matches!(reduction, Reduction::ArgMin { .. });
        let b = out.b.unwrap_or(out.a);
        rec.dispatch_indirect(
            &self.init,
            &[header, keys, seg, out.keys, out.a, b, out.count],
            &ModePush {
                mode: argmin as u32,
            },
            scratch,
            args,
        )?;
        rec.barrier();
        match reduction {
            Reduction::Sum { values } => {
                self.reduce_pass(rec, 0, [header, seg, values, values, out.a, b], scratch)?;
            }
            Reduction::Count => {
                self.reduce_pass(rec, 1, [header, seg, seg, seg, out.a, b], scratch)?;
            }
            Reduction::ArgMin { t, ids } => {
                self.reduce_pass(rec, 2, [header, seg, t, ids, out.a, b], scratch)?;
                self.reduce_pass(rec, 3, [header, seg, t, ids, out.a, b], scratch)?;
                rec.dispatch_indirect(
                    &self.finish,
                    &[header, keys, seg, out.a],
                    &(),
                    scratch,
                    args,
                )?;
                rec.barrier();
            }
        }
        Ok(())
    }

    /// The segment variant (see the module documentation).
    #[allow(clippy::too_many_arguments)]
    fn record_segments(
        &self,
        rec: &mut Recorder,
        kernels: &SegmentKernels,
        count: Count<'_>,
        keys: BufferSlice<'_>,
        reduction: Reduction<'_>,
        out: RunOutputs<'_>,
        scratch: &Buffer,
    ) -> Result<()> {
        let cap = count.capacity();
        let (heads_off, scan_off) = self.layout(cap);
        let header = scratch.slice(0, HEADER_BYTES);
        let heads = scratch.slice(heads_off, region(self.ids_len(cap) as u64 * 4));
        let items = kernels.items;
        // Kind 0 counts the segments, kind 1 their workgroups (as the segment scan does).
        self.setup.record(
            rec,
            count,
            1,
            header,
            [items, items * self.tuning.workgroup_size, 0, 0],
            Some(out.count),
        )?;
        rec.dispatch_indirect(
            &kernels.heads,
            &[header, keys, heads],
            &(),
            scratch,
            args_offset(1),
        )?;
        rec.barrier();
        // The scan's n is the segment count just written to the header (word HDR_GROUPS).
        let segments = Count::Gpu {
            buffer: scratch,
            offset: 4,
            max: self.ids_len(cap),
        };
        self.scan.record_count(
            rec,
            segments,
            heads,
            heads,
            ScanKind::Exclusive,
            false,
            scratch,
            scan_off,
        )?;
        let (kernel, a, b) = match reduction {
            Reduction::Sum { values } => (&kernels.reduce[0], values, values),
            Reduction::Count => (&kernels.reduce[1], keys, keys),
            Reduction::ArgMin { t, ids } => (&kernels.reduce[2], t, ids),
        };
        let out_b = out.b.unwrap_or(out.a);
        rec.dispatch_indirect(
            kernel,
            &[header, keys, heads, a, b, out.keys, out.a, out_b, out.count],
            &(),
            scratch,
            args_offset(1),
        )?;
        rec.barrier();
        Ok(())
    }

    fn reduce_pass(
        &self,
        rec: &mut Recorder,
        mode: u32,
        bindings: [BufferSlice<'_>; 6],
        scratch: &Buffer,
    ) -> Result<()> {
        rec.dispatch_indirect(
            &self.reduce,
            &bindings,
            &ModePush { mode },
            scratch,
            args_offset(0),
        )?;
        rec.barrier();
        Ok(())
    }
}
