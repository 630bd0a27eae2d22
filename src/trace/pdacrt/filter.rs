//! Filtering a level (Algorithm 2): each triangle and ray is classified against its
//! node's two halves, the level is split by those codes, and its children are sized,
//! with the one host round trip per level reading back the totals.

use super::kernels::*;
use super::level::{Filtered, IdList, Level, Ranks};
use super::types::{LevelTotals, CHANNELS, CHILD_BYTES, TILE_ITEMS};
use super::{bits_for, Chunk, PdacrtTracer};
use crate::primitives::{
    reduce_by_key::{Reduction, RunOutputs},
    scan::SMALL_SCAN_MAX,
    ScanKind,
};
use crate::trace::Query;
use crate::vk::{self, grid_for, Buffer, BufferSlice, MemoryKind, Recorder, StreamKind};

/// The buffers filtering a level writes: its side counts (prefix-sum split), its
/// children, their channels and the channels' scan, and the totals the host reads back
/// (the children's triangle bounds are the level's own: [`Level::bounds`]).
struct LevelOutputs {
    ranks: Option<Ranks>,
    children: Buffer,
    channels: Buffer,
    offsets: Buffer,
    stride: u32,
    summary: Buffer,
}

impl PdacrtTracer {
    /// Filters one level (Algorithm 1 lines 4–6, Algorithm 2) and reads its totals back:
    /// the loop's one host round trip per level. `hits_written`: whether a flush has
    /// written closest hits for the chunk (before that the ray filter skips reading them).
    pub(super) fn filter_level(
        &mut self,
        level: &Level,
        chunk: &Chunk<'_>,
        depth: u32,
        hits_written: bool,
    ) -> vk::Result<Filtered> {
        let gpu = self.gpu.clone();
        let out = self.take_level_outputs(level)?;
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.begin_scope("pdacrt-level")?;
        self.record_filters(&mut rec, level, chunk, &out, hits_written)?;
        let counts = self.record_plan(&mut rec, level, depth, &out)?;
        rec.end_scope()?;
        let done = rec.submit(&[])?;
        let totals = out.summary.read_after::<LevelTotals>(&done)?[0];
        self.scratch.retired.clear();
        self.pool.collect();
        self.pool.give(out.channels);
        if let Some((tri_counts, ray_counts)) = counts {
            self.pool.give(tri_counts);
            self.pool.give(ray_counts);
        }
        Ok(Filtered {
            totals,
            children: out.children,
            offsets: out.offsets,
            stride: out.stride,
            ranks: out.ranks,
        })
    }

    /// The buffers [`LevelOutputs`] for `level`, and scratch for its scans and sorts.
    fn take_level_outputs(&mut self, level: &Level) -> vk::Result<LevelOutputs> {
        let child_count = level.node_count * 2;
        // Channel stride: a multiple of 64 words keeps every channel slice aligned.
        let stride = child_count.next_multiple_of(64);
        let ranked = self.tiled();
        let ranks = ranked
            .then(|| -> vk::Result<Ranks> {
                let (t, r) = (level.tris.tiles + 1, level.rays.tiles + 1);
                Ok(Ranks {
                    buffer: self.pool.take("pdacrt-ranks", 2 * (t + r) as u64 * 4)?,
                    tri_left: 0,
                    tri_right: t,
                    ray_left: 2 * t,
                    ray_right: 2 * t + r,
                })
            })
            .transpose()?;
        let max_list = level.tris.total.max(level.rays.total);
        if !ranked {
            self.sort_scratch(max_list)?;
        }
        let scanned = ranks.as_ref().map_or(max_list, Ranks::len);
        self.misc_scratch(scanned.max(CHANNELS * stride), !ranked)?;
        let channel_bytes = (stride * CHANNELS) as u64 * 4;
        Ok(LevelOutputs {
            ranks,
            children: self
                .pool
                .take("pdacrt-children", child_count as u64 * CHILD_BYTES)?,
            channels: self.pool.take("pdacrt-channels", channel_bytes)?,
            offsets: self.pool.take("pdacrt-offsets", channel_bytes)?,
            stride,
            summary: self.gpu.create_buffer(
                "pdacrt-level-totals",
                size_of::<LevelTotals>() as u64,
                MemoryKind::Readback,
            )?,
        })
    }

    /// Algorithm 2 lines 2–6: the status codes of the level's triangles, then of its
    /// rays (and, split by prefix sums, each tile's side counts).
    fn record_filters(
        &self,
        rec: &mut Recorder,
        level: &Level,
        chunk: &Chunk<'_>,
        out: &LevelOutputs,
        hits_written: bool,
    ) -> vk::Result<()> {
        let ranked = out.ranks.is_some();
        let tight = self.params.tight_boxes;
        let (tri_bases, ray_bases) = Ranks::bases(out.ranks.as_ref());
        let ranks = out.ranks.as_ref().map(|r| BufferSlice::from(&r.buffer));
        // Ranked: one workgroup per tile; sorted: one invocation per id.
        let groups = |list: &IdList, pipeline: &vk::ComputePipeline| {
            if ranked {
                grid_for(&self.gpu, list.tiles as u64, 1)
            } else {
                grid_for(&self.gpu, list.total as u64, pipeline.workgroup_size())
            }
        };
        let dispatched = |list: &IdList| if ranked { list.tiles } else { list.total };
        let mut bindings: Vec<BufferSlice> = vec![
            (&self.triangles).into(),
            (&level.nodes).into(),
            (&level.tris.ids).into(),
            (&level.tris.owner).into(),
        ];
        bindings.extend(ranks);
        bindings.push((&level.bounds).into());
        rec.dispatch(
            &self.kernels.filter_triangles,
            &bindings,
            &FilterTrianglesPush {
                n: dispatched(&level.tris),
                eps: self.eps,
                left_base: tri_bases.0,
                right_base: tri_bases.1,
                tight: tight as u32,
            },
            groups(&level.tris, &self.kernels.filter_triangles),
        )?;
        if tight {
            // The rays are filtered against the children's boxes the triangles just gave.
            rec.barrier();
        }
        let mut bindings: Vec<BufferSlice> = vec![
            chunk.rays.into(),
            (&level.nodes).into(),
            (&level.rays.ids).into(),
            (&level.rays.owner).into(),
            chunk.hits.into(),
        ];
        bindings.extend(ranks);
        bindings.push((&level.bounds).into());
        rec.dispatch(
            &self.kernels.filter_rays,
            &bindings,
            &FilterRaysPush {
                n: dispatched(&level.rays),
                eps: self.eps,
                occlusion: (chunk.query == Query::Occlusion) as u32,
                ray_offset: chunk.offset,
                left_base: ray_bases.0,
                right_base: ray_bases.1,
                tight: tight as u32,
                hits_written: hits_written as u32,
            },
            groups(&level.rays, &self.kernels.filter_rays),
        )?;
        rec.barrier();
        Ok(())
    }

    /// Algorithm 2 lines 7–15 and Algorithm 1 lines 6 and 11, after the filters: the
    /// split (ranked: the scan of the side counts; sorted: sorting and counting each
    /// list), the children, the scan of their channels into positions and the level's
    /// totals. Sorted, returns the per-node count tables (the caller frees them).
    fn record_plan(
        &mut self,
        rec: &mut Recorder,
        level: &Level,
        depth: u32,
        out: &LevelOutputs,
    ) -> vk::Result<Option<(Buffer, Buffer)>> {
        let push = self.children_push(level, depth, out);
        let channel_words = CHANNELS * out.stride;
        // The split: ranked, the scan of the side counts (or all of the plan in one
        // dispatch); sorted, the sort and the per-node count tables.
        let counts = match &out.ranks {
            Some(ranks)
                if self.params.one_dispatch_plan
                    && ranks.len().max(channel_words) <= SMALL_SCAN_MAX =>
            {
                rec.dispatch(
                    &self.kernels.level_plan,
                    &[
                        (&level.nodes).into(),
                        (&ranks.buffer).into(),
                        (&out.children).into(),
                        (&out.channels).into(),
                        (&level.bounds).into(),
                        (&out.offsets).into(),
                        (&out.summary).into(),
                    ],
                    &LevelPlanPush {
                        children: push,
                        ranks_len: ranks.len(),
                    },
                    [1, 1, 1],
                )?;
                return Ok(None);
            }
            Some(ranks) => {
                // Every tile-count array in one exclusive scan: each array's ranks come
                // out offset by the arrays before it, which cancels in every use (a
                // child's size and an element's offset are differences of ranks).
                let all = (&ranks.buffer).into();
                let misc = self.scratch.misc.as_ref().unwrap();
                self.scan
                    .record(rec, ranks.len(), all, all, ScanKind::Exclusive, misc)?;
                None
            }
            None => Some(self.record_sort_split(rec, level)?),
        };
        self.record_children(rec, level, out, counts.as_ref(), &push)?;
        self.record_positions_and_totals(rec, out, push.child_count)?;
        Ok(counts)
    }

    /// What the children's kernels of `level` (at `depth`) take, beside their buffers.
    fn children_push(&self, level: &Level, depth: u32, out: &LevelOutputs) -> ChildrenPush {
        let (tri_bases, ray_bases) = Ranks::bases(out.ranks.as_ref());
        ChildrenPush {
            child_count: level.node_count * 2,
            stride: out.stride,
            alpha: self.params.alpha,
            beta: self.params.beta,
            last_level: (depth + 1 >= self.params.max_depth) as u32,
            min_extent: self.eps * 4.0,
            max_segment_rays: self.params.max_segment_rays(),
            tile_items: TILE_ITEMS,
            tri_left_base: tri_bases.0,
            tri_right_base: tri_bases.1,
            ray_left_base: ray_bases.0,
            ray_right_base: ray_bases.1,
            tight: self.params.tight_boxes as u32,
            terminal_cost: self.params.terminal_cost_at(level.rays.total),
        }
    }

    /// The children of the level's nodes, from the split: the ranks, or (sorted) the
    /// `counts` tables.
    fn record_children(
        &self,
        rec: &mut Recorder,
        level: &Level,
        out: &LevelOutputs,
        counts: Option<&(Buffer, Buffer)>,
        push: &ChildrenPush,
    ) -> vk::Result<()> {
        // The children read the split's tables: the scanned side counts, or the
        // triangle and ray count tables.
        let mut bindings: Vec<BufferSlice> = vec![(&level.nodes).into()];
        match counts {
            Some((tri_counts, ray_counts)) => {
                bindings.extend([BufferSlice::from(tri_counts), ray_counts.into()])
            }
            None => bindings.extend(out.ranks.iter().map(|r| BufferSlice::from(&r.buffer))),
        }
        bindings.extend([
            BufferSlice::from(&out.children),
            (&out.channels).into(),
            (&level.bounds).into(),
        ]);
        rec.dispatch_items(
            &self.kernels.children,
            &bindings,
            push,
            push.child_count as u64,
        )?;
        rec.barrier();
        Ok(())
    }

    /// Algorithm 1 line 11: positions of the next level and of the terminal nodes, and
    /// the level's totals.
    fn record_positions_and_totals(
        &self,
        rec: &mut Recorder,
        out: &LevelOutputs,
        child_count: u32,
    ) -> vk::Result<()> {
        // One scan runs through all the channels back to back; each channel's offsets
        // come out raised by the channels before it (and by the unwritten padding up to
        // `stride`), which the readers subtract (channel_offset in pdacrt.glsl).
        let misc = self.scratch.misc.as_ref().unwrap();
        self.scan.record(
            rec,
            CHANNELS * out.stride,
            (&out.channels).into(),
            (&out.offsets).into(),
            ScanKind::Exclusive,
            misc,
        )?;
        rec.dispatch(
            &self.kernels.level_summary,
            &[
                (&out.channels).into(),
                (&out.offsets).into(),
                (&out.summary).into(),
            ],
            &SummaryPush {
                child_count,
                stride: out.stride,
            },
            [1, 1, 1],
        )
    }

    /// The paper's split ([`LevelSplit::SortByKey`]): sorts each list by status key
    /// (Figure 4) and counts each (node, code) run (Algorithm 2 lines 9–12) into
    /// per-node, per-code tables for `children`. Returns the triangle and ray tables.
    fn record_sort_split(
        &mut self,
        rec: &mut Recorder,
        level: &Level,
    ) -> vk::Result<(Buffer, Buffer)> {
        let max_list = level.tris.total.max(level.rays.total);
        // At most 4 runs per node: one per status code.
        let max_runs = max_list.min(level.node_count * 4) as u64;
        let run_keys = self.pool.take("pdacrt-run-keys", max_runs * 4)?;
        let run_counts = self.pool.take("pdacrt-run-counts", max_runs * 4)?;
        let run_total = self.pool.take("pdacrt-run-total", 4)?;
        let tri_counts = self
            .pool
            .take("pdacrt-tri-counts", level.node_count as u64 * 16)?;
        let ray_counts = self
            .pool
            .take("pdacrt-ray-counts", level.node_count as u64 * 16)?;
        let (_, sort_scratch) = self.scratch.sort.as_ref().unwrap();
        let misc = self.scratch.misc.as_ref().unwrap();
        rec.fill(&tri_counts, 0);
        rec.fill(&ray_counts, 0);
        rec.barrier();
        let key_bits = 2 + bits_for(level.node_count);
        for (list_n, keys, ids, counts) in [
            (
                level.tris.total,
                &level.tris.owner,
                &level.tris.ids,
                &tri_counts,
            ),
            (
                level.rays.total,
                &level.rays.owner,
                &level.rays.ids,
                &ray_counts,
            ),
        ] {
            self.sort.record(
                rec,
                list_n,
                keys.into(),
                Some(ids.into()),
                0..key_bits,
                sort_scratch,
            )?;
            self.reduce.record(
                rec,
                list_n,
                keys.into(),
                Reduction::Count,
                RunOutputs {
                    keys: (&run_keys).into(),
                    a: (&run_counts).into(),
                    b: None,
                    count: (&run_total).into(),
                },
                misc,
            )?;
            rec.dispatch_items(
                &self.kernels.child_counts,
                &[
                    (&run_keys).into(),
                    (&run_counts).into(),
                    (&run_total).into(),
                    counts.into(),
                ],
                &MaxRunsPush { max_runs: list_n },
                (level.node_count * 4) as u64,
            )?;
            rec.barrier();
        }
        for b in [run_keys, run_counts, run_total] {
            self.pool.give(b);
        }
        Ok((tri_counts, ray_counts))
    }
}
