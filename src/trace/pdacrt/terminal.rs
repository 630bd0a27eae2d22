//! The terminal-node buffer: the levels fill it with terminal nodes, and flushes
//! intersect them by brute force (Algorithm 3) into the closest hits.

use super::kernels::*;
use super::types::{LevelTotals, Segment};
use super::{bits_for, Chunk, FlushReduce, PdacrtTracer};
use crate::primitives::{
    gather::Direction,
    reduce_by_key::{Reduction, RunOutputs},
};
use crate::trace::Query;
use crate::vk::{self, grid_for, Buffer, BufferSlice, Recorder, StreamKind};

/// The terminal-node buffer and its fill.
pub(super) struct TerminalBuffer {
    pub(super) tri_ids: Buffer,
    pub(super) ray_ids: Buffer,
    pub(super) segments: Buffer,
    pub(super) tri_capacity: u32,
    pub(super) ray_capacity: u32,
    pub(super) segment_capacity: u32,
    pub(super) tris: u32,
    pub(super) rays: u32,
    pub(super) segment_count: u32,
    /// Whether a flush has written closest hits for the chunk yet: until then every
    /// ray's is "none", and the ray filter need not read them.
    pub(super) hits_written: bool,
}

/// The arrays a flush sorts and reduces the terminal entries in: a word per entry each,
/// but `run_total`.
struct FlushArrays {
    /// Each entry's hit t; then, reused by the runs, each ray's closest.
    entry_t: Buffer,
    /// Each entry's hit triangle; then each ray's closest.
    entry_tri: Buffer,
    /// Each entry's ray id, sorted in place.
    keys: Buffer,
    /// The entries' order by ray id; then each run's ray id.
    order: Buffer,
    /// `entry_t` in ray order.
    sorted_t: Buffer,
    /// `entry_tri` in ray order.
    sorted_tri: Buffer,
    /// The number of runs (rays with an entry).
    run_total: Buffer,
}

impl TerminalBuffer {
    /// Counts a level's terminal nodes in, once its scatter has been recorded.
    pub(super) fn add(&mut self, totals: &LevelTotals) {
        self.tris += totals.term_tris;
        self.rays += totals.term_rays;
        self.segment_count += totals.term_nodes;
    }

    /// Counts the buffer empty, once a flush has been recorded.
    fn clear(&mut self) {
        self.tris = 0;
        self.rays = 0;
        self.segment_count = 0;
        self.hits_written = true;
    }
}

impl PdacrtTracer {
    /// A terminal-node buffer for `tri_capacity` triangle ids, `ray_capacity` ray ids and
    /// `segment_capacity` segments (at least 1024).
    pub(super) fn new_terminal_buffer(
        &mut self,
        tri_capacity: u32,
        ray_capacity: u32,
        segment_capacity: u32,
    ) -> vk::Result<TerminalBuffer> {
        let segment_capacity = segment_capacity.max(1024);
        Ok(TerminalBuffer {
            tri_ids: self
                .pool
                .take("pdacrt-term-tris", tri_capacity as u64 * 4)?,
            ray_ids: self
                .pool
                .take("pdacrt-term-rays", ray_capacity as u64 * 4)?,
            segments: self.pool.take(
                "pdacrt-term-segments",
                segment_capacity as u64 * size_of::<Segment>() as u64,
            )?,
            tri_capacity,
            ray_capacity,
            segment_capacity,
            tris: 0,
            rays: 0,
            segment_count: 0,
            hits_written: false,
        })
    }

    /// Returns the buffer's memory to the pool.
    pub(super) fn give_terminal(&mut self, term: TerminalBuffer) {
        self.pool.give(term.tri_ids);
        self.pool.give(term.ray_ids);
        self.pool.give(term.segments);
    }

    /// Grows the terminal buffer `term` where `tris` triangle ids, `rays` ray ids or
    /// `segments` segments exceed its capacity. The new buffer starts empty, as `term`
    /// is whenever it has to grow (the root's fresh buffer, or one a level just flushed).
    pub(super) fn fit_terminal(
        &mut self,
        term: &mut TerminalBuffer,
        tris: u32,
        rays: u32,
        segments: u32,
    ) -> vk::Result<()> {
        if tris > term.tri_capacity || rays > term.ray_capacity || segments > term.segment_capacity
        {
            let mut bigger = self.new_terminal_buffer(
                tris.max(term.tri_capacity),
                rays.max(term.ray_capacity),
                segments.max(term.segment_capacity),
            )?;
            bigger.hits_written = term.hits_written;
            let old = std::mem::replace(term, bigger);
            self.give_terminal(old);
        }
        Ok(())
    }

    /// Makes room in `term` for a level's terminal nodes (`totals`). Returns whether the
    /// level called for a flush (whether or not the buffer held anything to flush).
    pub(super) fn make_room(
        &mut self,
        term: &mut TerminalBuffer,
        totals: &LevelTotals,
        chunk: &Chunk<'_>,
    ) -> vk::Result<bool> {
        let lambda = self.params.lambda;
        // Algorithm 1 lines 7–10: flush first if this level's terminal nodes would
        // push the buffer past λ.
        let flushed = term.tris + totals.term_tris > lambda
            || term.rays + totals.term_rays > lambda
            || term.segment_count + totals.term_nodes > term.segment_capacity;
        if flushed && term.segment_count > 0 {
            self.flush(term, chunk)?;
        }
        // One level alone exceeds η: grow the (now empty) buffer to fit it.
        self.fit_terminal(term, totals.term_tris, totals.term_rays, totals.term_nodes)?;
        Ok(flushed)
    }

    /// Processes the terminal-node buffer (Algorithm 3) and updates the global closest
    /// hits (Algorithm 1 line 9). Recorded without a host wait.
    pub(super) fn flush(&mut self, term: &mut TerminalBuffer, chunk: &Chunk<'_>) -> vk::Result<()> {
        let gpu = self.gpu.clone();
        let entries = term.rays;
        self.stats.flushes += 1;
        if self.params.flush_reduce == FlushReduce::AtomicMin {
            return self.flush_atomic(term, chunk);
        }
        let arrays = self.take_flush_arrays(entries)?;
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.begin_scope("pdacrt-flush")?;
        // Algorithm 3 lines 2–10.
        self.record_segmented_intersect(
            &mut rec,
            term,
            chunk,
            &[(&arrays.entry_t).into(), (&arrays.entry_tri).into()],
        )?;
        // Lines 12–13: sort the entries by ray id, then the segmented arg-min.
        self.record_sort_by_ray(&mut rec, term, &arrays, chunk.n)?;
        self.record_arg_min(&mut rec, &arrays, entries)?;
        // Algorithm 1 line 9.
        rec.dispatch_items(
            &self.kernels.update_hits,
            &[
                (&arrays.order).into(),
                (&arrays.entry_t).into(),
                (&arrays.entry_tri).into(),
                (&arrays.run_total).into(),
                chunk.hits.into(),
            ],
            &UpdateHitsPush {
                max_runs: entries,
                ray_offset: chunk.offset,
            },
            entries as u64,
        )?;
        rec.barrier();
        rec.end_scope()?;
        rec.submit(&[])?;
        self.give_flush_arrays(arrays);
        term.clear();
        Ok(())
    }

    /// The [`FlushArrays`] for `entries` terminal entries, and scratch for their sort,
    /// gathers and reduction.
    fn take_flush_arrays(&mut self, entries: u32) -> vk::Result<FlushArrays> {
        self.sort_scratch(entries)?;
        self.misc_scratch(entries, true)?;
        let bytes = entries as u64 * 4;
        Ok(FlushArrays {
            entry_t: self.pool.take("pdacrt-entry-t", bytes)?,
            entry_tri: self.pool.take("pdacrt-entry-tri", bytes)?,
            keys: self.pool.take("pdacrt-entry-rays", bytes)?,
            order: self.pool.take("pdacrt-entry-order", bytes)?,
            sorted_t: self.pool.take("pdacrt-sorted-t", bytes)?,
            sorted_tri: self.pool.take("pdacrt-sorted-tri", bytes)?,
            run_total: self.pool.take("pdacrt-run-total", 4)?,
        })
    }

    /// Returns a flush's arrays to the pool.
    fn give_flush_arrays(&mut self, arrays: FlushArrays) {
        let FlushArrays {
            entry_t,
            entry_tri,
            keys,
            order,
            sorted_t,
            sorted_tri,
            run_total,
        } = arrays;
        for b in [
            entry_t, entry_tri, keys, order, sorted_t, sorted_tri, run_total,
        ] {
            self.pool.give(b);
        }
    }

    /// Sorts the entries' ray ids (`keys`, from the terminal buffer) with their order,
    /// and gathers their t and triangle into that order.
    fn record_sort_by_ray(
        &self,
        rec: &mut Recorder,
        term: &TerminalBuffer,
        arrays: &FlushArrays,
        chunk_rays: u32,
    ) -> vk::Result<()> {
        let entries = term.rays;
        let (_, sort_scratch) = self.scratch.sort.as_ref().unwrap();
        let misc = self.scratch.misc.as_ref().unwrap();
        rec.copy(&term.ray_ids, 0, &arrays.keys, 0, entries as u64 * 4);
        rec.dispatch_items(
            &self.kernels.iota,
            &[(&arrays.order).into(), (&arrays.sorted_t).into()],
            &IotaPush {
                n: entries,
                base: 0,
                tag: 0,
            },
            entries as u64,
        )?;
        rec.barrier();
        self.sort.record(
            rec,
            entries,
            (&arrays.keys).into(),
            Some((&arrays.order).into()),
            0..bits_for(chunk_rays),
            sort_scratch,
        )?;
        for (src, out) in [
            (&arrays.entry_t, &arrays.sorted_t),
            (&arrays.entry_tri, &arrays.sorted_tri),
        ] {
            self.gather.record(
                rec,
                entries,
                Direction::Gather,
                src.into(),
                (&arrays.order).into(),
                out.into(),
                misc,
            )?;
        }
        Ok(())
    }

    /// The segmented arg-min over the sorted entries: per ray, its closest t and
    /// triangle, into `order`, `entry_t` and `entry_tri`, and the ray count into
    /// `run_total`.
    fn record_arg_min(
        &self,
        rec: &mut Recorder,
        arrays: &FlushArrays,
        entries: u32,
    ) -> vk::Result<()> {
        let misc = self.scratch.misc.as_ref().unwrap();
        self.reduce.record(
            rec,
            entries,
            (&arrays.keys).into(),
            Reduction::ArgMin {
                t: (&arrays.sorted_t).into(),
                ids: (&arrays.sorted_tri).into(),
            },
            // The per-entry arrays are dead once gathered into sorted order: the runs
            // (at most one per entry) reuse them, which keeps a flush at six arrays.
            RunOutputs {
                keys: (&arrays.order).into(),
                a: (&arrays.entry_t).into(),
                b: Some((&arrays.entry_tri).into()),
                count: (&arrays.run_total).into(),
            },
            misc,
        )
    }

    /// The segmented intersection over the terminal buffer (Algorithm 3 lines 2–10): one
    /// workgroup per segment, writing into `outputs` (the per-entry t and triangle, or
    /// the packed closest hits for the atomic flush).
    fn record_segmented_intersect(
        &self,
        rec: &mut Recorder,
        term: &TerminalBuffer,
        chunk: &Chunk<'_>,
        outputs: &[BufferSlice<'_>],
    ) -> vk::Result<()> {
        let mut bindings: Vec<BufferSlice> = vec![
            (&self.triangles).into(),
            chunk.rays.into(),
            (&term.segments).into(),
            (&term.tri_ids).into(),
            (&term.ray_ids).into(),
        ];
        bindings.extend_from_slice(outputs);
        let groups = grid_for(&self.gpu, term.segment_count as u64, 1);
        rec.dispatch(
            &self.kernels.segmented_intersect,
            &bindings,
            &IntersectPush {
                segment_count: term.segment_count,
                ray_offset: chunk.offset,
                occlusion: (chunk.query == Query::Occlusion) as u32,
            },
            groups,
        )
    }

    /// [`FlushReduce::AtomicMin`]: the segmented intersection lowers each ray's packed
    /// closest hit in place (Algorithm 3 lines 2–10, with lines 12–13 and Algorithm 1
    /// line 9 folded into its atomicMin).
    fn flush_atomic(&mut self, term: &mut TerminalBuffer, chunk: &Chunk<'_>) -> vk::Result<()> {
        let gpu = self.gpu.clone();
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.begin_scope("pdacrt-flush")?;
        self.record_segmented_intersect(&mut rec, term, chunk, &[chunk.hits.into()])?;
        rec.barrier();
        rec.end_scope()?;
        rec.submit(&[])?;
        term.clear();
        Ok(())
    }
}
