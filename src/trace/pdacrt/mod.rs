//! PDACRT: Parallel Divide-and-Conquer Ray Tracing (Ravichandran & Narayanan, SIGGRAPH
//! Asia 2013; ../shared/papers/pdacrt-siggraph-asia-2013.txt and thesis chapter 2).
//!
//! No acceleration structure is built. The host drives Algorithm 1 as an explicit loop
//! over the levels of an implicit k-d hierarchy; each level is a handful of GPU passes
//! over linear id lists (filter → split by status code (a sort by key and run-length
//! counts, or a prefix scan) → child pivots → prefix sums → gather into the next level
//! or the terminal-node buffer). Terminal nodes are intersected in batches by the
//! segmented brute-force kernel of Algorithm 3, whose per-ray minima then reach the
//! global closest hits (a sort by ray id and a segmented arg-min, or atomics).
//!
//! Host round trips: one 32-byte readback per level (the level's totals, needed to size
//! the next level's lists and to decide a flush, Algorithm 1 lines 7 and 11); everything
//! else is chained on the GPU without waiting.
//!
//! Choices where the paper is silent, and why:
//! - Status codes are 0/1/2/3 (see pdacrt.glsl): the paper's 1..4 does not fit 2 bits.
//! - Child sizes come from run-length encoding of the sorted keys instead of summing
//!   codes and dividing (equivalent, and correct for code 0).
//! - Rays are clipped to the closest hit found by earlier flushes, so a ray leaves the
//!   hierarchy behind its hit once that hit is known (the breadth-first order of the
//!   paper cannot terminate rays early; flushes give a partial form of it for free).
//! - Triangle filtering is a bounding-box test along the split axis (conservative).
//! - A child also becomes terminal at `max_depth` or when thinner than `min_extent`, so
//!   coincident triangles cannot recurse forever.
//! - The terminal-node buffer grows when a single level produces more than η ids.
//! - Ray batches larger than `max_rays_per_chunk` are traced chunk by chunk.
//!
//! Where splitray departs from the paper's steps by default, both ways are kept and
//! selectable ([`PdacrtParams`]; `bench trace --split/--flush/--stage-triangles`), and
//! the tests check that they give the same hits:
//! - [`LevelSplit`]: the paper's sort by status key + reduce-by-key, or prefix sums of
//!   side flags (the default: the lists are already grouped by node, so the sort only
//!   partitions within nodes, which a scan does directly). The prefix-sum levels are
//!   cut into tiles of one node each (pdacrt.glsl), so no per-id key is kept, a node's
//!   box and routes are read once per tile, and only the tiles' side counts are
//!   scanned (a few words per 1024 elements instead of two per element).
//! - [`FlushReduce`]: the paper's sort by ray id + segmented arg-min, or one 64-bit
//!   atomicMin per entry (the default where the device has 64-bit buffer atomics).
//! - `stage_triangles`: the paper's shared-memory batches of T triangles, or direct
//!   reads with 8 rays per invocation (the default on CPU devices, where barriers are
//!   slow and shared memory is no nearer than any other memory).
//! - `tight_boxes`: a child's box is the bounds of its triangles within its half of the
//!   parent's box (the default), or the half itself as in the paper (Algorithm 2 line
//!   4). The triangles are filtered first, and the rays then against the children's
//!   boxes, so a ray that passes beside a half's geometry does not enter the child at
//!   all; the next split halves the geometry rather than empty space.
//! - `one_dispatch_plan`: with prefix sums, a level small enough for one workgroup
//!   scans its side counts, makes its children, scans their channels and writes its
//!   totals in one dispatch (the default) instead of four: on lavapipe a barrier
//!   between dispatches costs about 40 µs, a dozen of them per level.
//! - `terminal_cost`: a node below β rays stays in the loop while rays × triangles
//!   exceeds a budget of tests (the default), or is terminal as in the paper
//!   (Algorithm 1 line 6), however many triangles it brute-forces.

mod filter;
mod kernels;
mod level;
mod params;
mod pool;
mod terminal;
pub mod types;

pub use self::params::{FlushReduce, LevelSplit, PdacrtParams};

use std::time::Instant;

use glam::Vec3;
use serde::Serialize;

use self::kernels::*;
use self::level::{node_tiles, Filtered, IdList, Level, ListKind, NextBuffers, Ranks};
use self::pool::BufferPool;
use self::terminal::TerminalBuffer;
use self::types::{LevelTotals, Node, Segment, Tile, MAX_IDS, TILE_ITEMS};
use super::{GpuTriangle, Hit, Query, Tracer};
use crate::primitives::{Gather, RadixSort, ReduceByKey, Scan, SortScratch, Tuning};
use crate::vk::{
    self, grid_for, Buffer, BufferSlice, Gpu, MemoryKind, Recorder, StreamKind, TimelinePoint,
};

/// Bytes of a hit record: PDACRT keeps each ray's closest hit so far in its first half.
const HIT_BYTES: u64 = size_of::<Hit>() as u64;

/// What one level of the loop did (per-level statistics, on request).
#[derive(Clone, Debug, Default, Serialize)]
pub struct LevelStats {
    pub chunk: u32,
    pub level: u32,
    pub nodes: u32,
    /// Triangle ids in the level's list (triangles are duplicated across nodes).
    pub triangles: u32,
    /// Ray ids in the level's list.
    pub rays: u32,
    /// Ray ids per ray of the chunk.
    pub ray_duplication: f64,
    pub terminal_nodes: u32,
    pub flushed: bool,
    /// Host time from the level's first submission to reading its totals.
    pub ms: f64,
}

/// Totals of the last `trace` call.
#[derive(Clone, Debug, Default, Serialize)]
pub struct TraceStats {
    pub levels: Vec<LevelStats>,
    pub host_round_trips: u32,
    pub flushes: u32,
    pub chunks: u32,
}

/// The rays of one chunk and where their hits go.
#[derive(Clone, Copy)]
struct Chunk<'a> {
    rays: &'a Buffer,
    /// The hit buffer; the chunk's records double as its closest hits so far
    /// (BEST_SLOT in pdacrt.glsl).
    hits: &'a Buffer,
    /// The chunk's first ray in `rays` (and hit in `hits`).
    offset: u32,
    /// Rays in the chunk.
    n: u32,
    query: Query,
    /// The chunk's number within its trace call.
    index: u32,
}

/// Reusable scratch of the primitives, grown on demand.
#[derive(Default)]
struct Scratch {
    sort: Option<(u32, SortScratch)>,
    misc: Option<Buffer>,
    /// Outgrown scratch that submitted work may still read: freed at the next host wait
    /// (all PDACRT work is in order on one stream, so that wait covers it).
    retired: Vec<Buffer>,
}

pub struct PdacrtTracer {
    gpu: Gpu,
    params: PdacrtParams,
    kernels: Kernels,
    sort: RadixSort,
    reduce: ReduceByKey,
    scan: Scan,
    gather: Gather,
    triangles: Buffer,
    triangle_count: u32,
    scene_min: Vec3,
    scene_max: Vec3,
    /// Padding of every box test, relative to the scene's size.
    eps: f32,
    pool: BufferPool,
    scratch: Scratch,
    stats: TraceStats,
}

/// The box around the triangles and the padding of every box test: 1e-5 of the larger
/// of the scene's extent and its distance from the origin, well above float rounding of
/// coordinates that size.
fn scene_box(triangles: &[GpuTriangle]) -> (Vec3, Vec3, f32) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for (t_lo, t_hi) in triangles.iter().map(GpuTriangle::bounds) {
        lo = lo.min(t_lo);
        hi = hi.max(t_hi);
    }
    if triangles.is_empty() {
        (lo, hi) = (Vec3::ZERO, Vec3::ZERO);
    }
    let extent = (hi - lo)
        .max_element()
        .max(lo.abs().max(hi.abs()).max_element())
        .max(1e-6);
    (lo, hi, extent * 1e-5)
}

/// Triangle and chunk-local ray ids must stay below 2^30: the ranked kernels keep a
/// status code in the top two bits of each id.
fn check_id_range(triangles: usize) -> vk::Result<()> {
    if triangles >= MAX_IDS as usize {
        return Err(vk::VkError::Usage(format!(
            "PDACRT traces at most {} triangles, not {triangles}",
            MAX_IDS - 1
        )));
    }
    Ok(())
}

fn bits_for(count: u32) -> u32 {
    32 - count.saturating_sub(1).leading_zeros()
}

impl PdacrtTracer {
    pub fn new(gpu: &Gpu, triangles: &[GpuTriangle]) -> vk::Result<Self> {
        Self::with_params(gpu, triangles, PdacrtParams::for_device(gpu))
    }

    pub fn with_params(
        gpu: &Gpu,
        triangles: &[GpuTriangle],
        params: PdacrtParams,
    ) -> vk::Result<Self> {
        params.validate(&gpu.info().limits)?;
        check_id_range(triangles.len())?;
        if params.flush_reduce == FlushReduce::AtomicMin
            && !gpu.info().capabilities.buffer_int64_atomics
        {
            return Err(vk::VkError::Usage(format!(
                "PDACRT parameters: the atomic flush needs shaderBufferInt64Atomics, which {} lacks",
                gpu.info().name
            )));
        }
        let tuning = Tuning::for_device(gpu.info());
        let (lo, hi, eps) = scene_box(triangles);
        Ok(Self {
            gpu: gpu.clone(),
            params,
            kernels: Kernels::new(gpu, &params)?,
            sort: RadixSort::new(gpu, &tuning)?,
            reduce: ReduceByKey::new(gpu, &tuning)?,
            scan: Scan::new(gpu, &tuning)?,
            gather: Gather::new(gpu, &tuning)?,
            triangles: gpu.upload("pdacrt-triangles", triangles)?,
            triangle_count: triangles.len() as u32,
            scene_min: lo,
            scene_max: hi,
            eps,
            pool: BufferPool::new(gpu),
            scratch: Scratch::default(),
            stats: TraceStats::default(),
        })
    }

    pub fn params(&self) -> &PdacrtParams {
        &self.params
    }

    /// Statistics of the last `trace` call.
    pub fn stats(&self) -> &TraceStats {
        &self.stats
    }

    /// Frees pooled memory between frames (the next trace allocates again), after
    /// waiting for the work that may still use it.
    pub fn release_memory(&mut self) -> vk::Result<()> {
        self.gpu.wait_idle()?;
        self.pool.clear();
        self.scratch = Scratch::default();
        Ok(())
    }

    fn sort_scratch(&mut self, n: u32) -> vk::Result<()> {
        if self.scratch.sort.as_ref().is_none_or(|(cap, _)| *cap < n) {
            let cap = n.max(1024).next_power_of_two();
            let fresh = self.sort.alloc_scratch(&self.gpu, cap)?;
            if let Some((_, old)) = self.scratch.sort.replace((cap, fresh)) {
                self.scratch
                    .retired
                    .extend([old.keys, old.values, old.misc]);
            }
        }
        Ok(())
    }

    /// Scratch for scans of up to `n` items, and with `sort_path` for the reduce-by-key
    /// and gathers of the sort-based split and flush too (those need far more).
    fn misc_scratch(&mut self, n: u32, sort_path: bool) -> vk::Result<()> {
        let mut need = self.scan.scratch_bytes(n);
        if sort_path {
            need = need
                .max(self.reduce.scratch_bytes(n))
                .max(self.gather.scratch_bytes(n));
        }
        if self.scratch.misc.as_ref().is_none_or(|b| b.size() < need) {
            let bytes = need.next_power_of_two();
            let fresh = self
                .gpu
                .create_buffer("pdacrt-scratch", bytes, MemoryKind::Device)?;
            self.scratch
                .retired
                .extend(self.scratch.misc.replace(fresh));
        }
        Ok(())
    }

    fn iota(
        &self,
        rec: &mut Recorder,
        ids: &Buffer,
        tags: &Buffer,
        n: u32,
        base: u32,
        tag: u32,
    ) -> vk::Result<()> {
        rec.dispatch_items(
            &self.kernels.iota,
            &[ids.into(), tags.into()],
            &IotaPush { n, base, tag },
            n as u64,
        )
    }

    /// `ids[i] = i` for `i < n`.
    fn iota_ids(&self, rec: &mut Recorder, ids: &Buffer, n: u32) -> vk::Result<()> {
        rec.dispatch_items(
            &self.kernels.iota_ids,
            &[ids.into()],
            &IotaPush { n, base: 0, tag: 0 },
            n as u64,
        )
    }

    /// Traces rays `offset..offset + n` of `rays` into the same slots of `hits`.
    fn trace_chunk(&mut self, chunk: Chunk<'_>) -> vk::Result<()> {
        let Chunk {
            rays,
            hits,
            offset,
            n,
            ..
        } = chunk;
        let gpu = self.gpu.clone();
        // The closest hits so far, (triangle, ordered t) per ray, kept in the chunk's own
        // hit records (BEST_SLOT in pdacrt.glsl): all ones is above every hit and means
        // none yet.
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.fill_range(
            hits,
            offset as u64 * HIT_BYTES,
            n as u64 * HIT_BYTES,
            u32::MAX,
        )?;
        let p = self.params;
        // Segments: a terminal node holds ≥ 1 ray and typically hundreds, so η/64 of them
        // rarely bind (a full segment table flushes like a full id buffer: line 7).
        let mut term = self.new_terminal_buffer(p.eta, p.eta, p.eta / 64)?;
        let mut level = self.root_level(&mut rec, &mut term, n)?;
        rec.submit(&[])?;

        let mut depth = 0u32;
        while let Some(current) = level.take() {
            level = self.process_level(current, &mut term, &chunk, depth)?;
            depth += 1;
        }

        // Lines 18–20: the remaining terminal nodes.
        if term.segment_count > 0 {
            self.flush(&mut term, &chunk)?;
        }
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &self.kernels.finalize_hits,
            &[(&self.triangles).into(), rays.into(), hits.into()],
            &FinalizePush {
                n,
                ray_offset: offset,
            },
            n as u64,
        )?;
        rec.submit(&[])?;
        self.give_terminal(term);
        Ok(())
    }

    /// Levels split by prefix sums are cut into tiles; sorted ones carry per-id keys.
    fn tiled(&self) -> bool {
        self.params.split == LevelSplit::PrefixSums
    }

    /// Algorithm 1 line 2: the root level of a chunk of `n` rays, recorded into `rec`.
    /// A root already below α or β is terminal: it goes into `term` at once, and no
    /// level is left to loop over.
    fn root_level(
        &mut self,
        rec: &mut Recorder,
        term: &mut TerminalBuffer,
        n: u32,
    ) -> vk::Result<Option<Level>> {
        let tris = self.triangle_count;
        if tris == 0 {
            Ok(None) // every ray misses
        } else if self.params.is_terminal(tris, n, n) {
            self.root_terminal(rec, term, n)?;
            Ok(None)
        } else {
            self.root_lists(rec, n).map(Some)
        }
    }

    /// The terminal root: every triangle against every ray, the rays cut into segments
    /// of at most `max_segment_rays`.
    fn root_terminal(
        &mut self,
        rec: &mut Recorder,
        term: &mut TerminalBuffer,
        n: u32,
    ) -> vk::Result<()> {
        let tris = self.triangle_count;
        let per = self.params.max_segment_rays();
        let segment_count = n.div_ceil(per);
        self.fit_terminal(term, tris, n, segment_count)?;
        let seg_tags = self.pool.take("pdacrt-tags", tris.max(n) as u64 * 4)?;
        self.iota(rec, &term.tri_ids, &seg_tags, tris, 0, 0)?;
        self.iota(rec, &term.ray_ids, &seg_tags, n, 0, 0)?;
        let segments: Vec<Segment> = (0..segment_count)
            .map(|k| Segment {
                tri_start: 0,
                tri_count: tris,
                ray_start: k * per,
                ray_count: per.min(n - k * per),
            })
            .collect();
        // vkCmdUpdateBuffer takes at most 64 KiB at a time.
        for (i, part) in segments.chunks(4096).enumerate() {
            rec.update(
                &term.segments,
                (i * 4096 * size_of::<Segment>()) as u64,
                part,
            )?;
        }
        rec.barrier();
        term.tris = tris;
        term.rays = n;
        term.segment_count = segments.len() as u32;
        self.pool.give(seg_tags);
        Ok(())
    }

    /// The root's lists: one node around the scene, holding every triangle and all `n`
    /// rays of the chunk.
    fn root_lists(&mut self, rec: &mut Recorder, n: u32) -> vk::Result<Level> {
        let tris = self.triangle_count;
        let tiled = self.tiled();
        let root = Node {
            box_min: (self.scene_min - self.eps).into(),
            first_tri_tile: 0,
            box_max: (self.scene_max + self.eps).into(),
            first_ray_tile: 0,
            tri_start: 0,
            tri_count: tris,
            ray_start: 0,
            ray_count: n,
        };
        let pool = &mut self.pool;
        let tiles = |count: u32| tiled.then(|| count.div_ceil(TILE_ITEMS));
        let tight = self.params.tight_boxes;
        let level = Level {
            nodes: pool.take("pdacrt-nodes", size_of::<Node>() as u64)?,
            node_count: 1,
            tris: IdList::take(pool, ListKind::Triangles, tris, tiles(tris), false)?,
            rays: IdList::take(pool, ListKind::Rays, n, tiles(n), false)?,
            bounds: pool.take("pdacrt-bounds", Level::bounds_bytes(1, tight))?,
        };
        rec.update(&level.nodes, 0, &[root])?;
        level.record_bounds_fill(rec, tight)?;
        for (ids, owner, count) in [
            (&level.tris.ids, &level.tris.owner, tris),
            (&level.rays.ids, &level.rays.owner, n),
        ] {
            if tiled {
                self.iota_ids(rec, ids, count)?;
                let tiles: Vec<Tile> = node_tiles(0, 0, count).collect();
                // vkCmdUpdateBuffer takes at most 64 KiB at a time.
                for (i, part) in tiles.chunks(4096).enumerate() {
                    rec.update(owner, (i * 4096 * size_of::<Tile>()) as u64, part)?;
                }
            } else {
                self.iota(rec, ids, owner, count, 0, 0)?;
            }
        }
        rec.barrier();
        Ok(level)
    }

    /// One pass of Algorithm 1's loop (lines 3–16) over `current`, the level at `depth`:
    /// its terminal nodes go into `term`, the other children make the next level, which
    /// it returns.
    fn process_level(
        &mut self,
        current: Level,
        term: &mut TerminalBuffer,
        chunk: &Chunk<'_>,
        depth: u32,
    ) -> vk::Result<Option<Level>> {
        let started = Instant::now();
        let filtered = self.filter_level(&current, chunk, depth, term.hits_written)?;
        self.stats.host_round_trips += 1;
        let totals = filtered.totals;
        let child_count = current.node_count * 2;
        let (next, routes) = self.take_next_level(&totals, child_count)?;
        let flushed = self.make_room(term, &totals, chunk)?;
        self.record_write_and_scatter(&current, next.as_ref(), &filtered, &routes, term)?;
        term.add(&totals);
        self.record_level_stats(&current, &totals, flushed, chunk, depth, started);
        // Line 16: the current level's lists go back to the pool.
        self.give_level(current, filtered, routes);
        Ok(next)
    }

    /// The buffers of the next level (none when `totals` has no next nodes) and the
    /// routes of the current level's `child_count` children.
    fn take_next_level(
        &mut self,
        totals: &LevelTotals,
        child_count: u32,
    ) -> vk::Result<(Option<Level>, Buffer)> {
        let tiled = self.tiled();
        let tight = self.params.tight_boxes;
        let pool = &mut self.pool;
        // Lines 11–15 (recorded by record_write_and_scatter): the next level's lists.
        // Taken while nothing is in flight (filter_level waited), so the buffers the pool
        // lets go to make room go at once instead of at the next wait, and whatever stays
        // free after these takes is freed too (the next level allocates what it misses):
        // peak memory.
        let next = (totals.next_nodes > 0)
            .then(|| -> vk::Result<Level> {
                // Largest first (see take_while_idle).
                let rays = IdList::take(
                    pool,
                    ListKind::Rays,
                    totals.next_rays,
                    tiled.then_some(totals.next_ray_tiles),
                    true,
                )?;
                let tris = IdList::take(
                    pool,
                    ListKind::Triangles,
                    totals.next_tris,
                    tiled.then_some(totals.next_tri_tiles),
                    true,
                )?;
                Ok(Level {
                    nodes: pool.take_while_idle(
                        "pdacrt-nodes",
                        totals.next_nodes as u64 * size_of::<Node>() as u64,
                    )?,
                    node_count: totals.next_nodes,
                    tris,
                    rays,
                    bounds: pool.take_while_idle(
                        "pdacrt-bounds",
                        Level::bounds_bytes(totals.next_nodes, tight),
                    )?,
                })
            })
            .transpose()?;
        let routes = pool.take_while_idle("pdacrt-routes", child_count as u64 * 16)?;
        pool.clear(); // only free buffers: the taken ones are not in the pool
        Ok((next, routes))
    }

    /// Lines 11–15 in one submission, without a host wait: write_nodes places the next
    /// level's nodes and the terminal segments, then scatter moves each id of `current`
    /// into the next level or the terminal buffer.
    fn record_write_and_scatter(
        &self,
        current: &Level,
        next: Option<&Level>,
        filtered: &Filtered,
        routes: &Buffer,
        term: &TerminalBuffer,
    ) -> vk::Result<()> {
        let mut rec = self.gpu.recorder(StreamKind::Main)?;
        if let Some(next) = next {
            // Ordered before the next level's filters by the barriers below.
            next.record_bounds_fill(&mut rec, self.params.tight_boxes)?;
        }
        let empty = &term.segments; // bound where a list is empty; never written then
        let next = NextBuffers::new(next, empty);
        let child_count = current.node_count * 2;
        self.record_write_nodes(&mut rec, child_count, &next, filtered, routes, term)?;
        rec.barrier();
        self.record_scatter(&mut rec, current, &next, filtered, routes, term)?;
        rec.barrier();
        rec.submit(&[])?;
        Ok(())
    }

    /// Records write_nodes, which writes the next level's nodes (and, split by prefix
    /// sums, its tiles), the terminal segments and each child's route.
    fn record_write_nodes(
        &self,
        rec: &mut Recorder,
        child_count: u32,
        next: &NextBuffers<'_>,
        filtered: &Filtered,
        routes: &Buffer,
        term: &TerminalBuffer,
    ) -> vk::Result<()> {
        let mut bindings: Vec<BufferSlice> = vec![
            (&filtered.children).into(),
            (&filtered.offsets).into(),
            next.nodes.into(),
            (&term.segments).into(),
            routes.into(),
        ];
        if self.tiled() {
            // The next level's tiles (its keys are written by the scatter instead).
            bindings.extend([
                BufferSlice::from(next.tri_owner),
                BufferSlice::from(next.ray_owner),
            ]);
        }
        rec.dispatch_items(
            &self.kernels.write_nodes,
            &bindings,
            &WriteNodesPush {
                child_count,
                stride: filtered.stride,
                segment_base: term.segment_count,
                term_tri_base: term.tris,
                term_ray_base: term.rays,
                max_segment_rays: self.params.max_segment_rays(),
                tile_items: TILE_ITEMS,
            },
            child_count as u64,
        )
    }

    /// Records scatter, which moves each id of `current` to its place in the next level
    /// or in the terminal buffer.
    fn record_scatter(
        &self,
        rec: &mut Recorder,
        current: &Level,
        next: &NextBuffers<'_>,
        filtered: &Filtered,
        routes: &Buffer,
        term: &TerminalBuffer,
    ) -> vk::Result<()> {
        let ranks = filtered.ranks.as_ref();
        let (tri_sides, ray_sides) = Ranks::bases(ranks);
        for (rays_list, list, next_ids, next_owner, term_ids, sides) in [
            (
                0,
                &current.tris,
                next.tri_ids,
                next.tri_owner,
                &term.tri_ids,
                tri_sides,
            ),
            (
                1,
                &current.rays,
                next.ray_ids,
                next.ray_owner,
                &term.ray_ids,
                ray_sides,
            ),
        ] {
            let push = ScatterPush {
                n: list.total,
                rays: rays_list,
                left_base: sides.0,
                right_base: sides.1,
            };
            match ranks {
                // One workgroup per tile.
                Some(ranks) => rec.dispatch(
                    &self.kernels.scatter,
                    &[
                        (&list.owner).into(),
                        (&list.ids).into(),
                        routes.into(),
                        next_ids.into(),
                        term_ids.into(),
                        (&ranks.buffer).into(),
                    ],
                    &push,
                    grid_for(&self.gpu, list.tiles as u64, 1),
                )?,
                None => rec.dispatch_items(
                    &self.kernels.scatter,
                    &[
                        (&list.owner).into(),
                        (&list.ids).into(),
                        routes.into(),
                        next_ids.into(),
                        next_owner.into(),
                        term_ids.into(),
                    ],
                    &push,
                    list.total as u64,
                )?,
            }
        }
        Ok(())
    }

    /// Records the statistics of `current`, the level at `depth`, whose time runs from
    /// `started` (before its filtering).
    fn record_level_stats(
        &mut self,
        current: &Level,
        totals: &LevelTotals,
        flushed: bool,
        chunk: &Chunk<'_>,
        depth: u32,
        started: Instant,
    ) {
        crate::timeline_counter!("pdacrt", "rays per level", current.rays.total);
        self.stats.levels.push(LevelStats {
            chunk: chunk.index,
            level: depth,
            nodes: current.node_count,
            triangles: current.tris.total,
            rays: current.rays.total,
            ray_duplication: current.rays.total as f64 / chunk.n.max(1) as f64,
            terminal_nodes: totals.term_nodes,
            flushed,
            ms: started.elapsed().as_secs_f64() * 1e3,
        });
    }

    /// Returns a finished level's buffers, and what filtering and routing it left, to
    /// the pool.
    fn give_level(&mut self, current: Level, filtered: Filtered, routes: Buffer) {
        current.give(&mut self.pool);
        for b in [filtered.children, filtered.offsets, routes] {
            self.pool.give(b);
        }
        if let Some(ranks) = filtered.ranks {
            self.pool.give(ranks.buffer);
        }
    }
}

impl Tracer for PdacrtTracer {
    fn name(&self) -> &'static str {
        "pdacrt"
    }

    fn level_stats(&self) -> Option<&TraceStats> {
        Some(&self.stats)
    }

    /// PDACRT builds nothing: new geometry is an upload and a new scene box.
    fn set_geometry(&mut self, triangles: &[GpuTriangle]) -> vk::Result<()> {
        check_id_range(triangles.len())?;
        self.gpu.wait_idle()?;
        let (lo, hi, eps) = scene_box(triangles);
        // In place where the old buffer fits (a dynamic scene's usual case), else the old
        // buffer goes before the new one comes: never both at once (peak memory).
        let bytes = std::mem::size_of_val(triangles) as u64;
        if bytes > self.triangles.size() {
            self.triangles = self
                .gpu
                .create_buffer("pdacrt-triangles", 4, MemoryKind::Device)?;
            self.triangles = self.gpu.upload("pdacrt-triangles", triangles)?;
        } else {
            self.triangles.write(triangles)?;
        }
        self.triangle_count = triangles.len() as u32;
        (self.scene_min, self.scene_max, self.eps) = (lo, hi, eps);
        Ok(())
    }

    /// Nothing to rebuild: the changed ranges are written over the old triangles in
    /// place, and the scene box is computed again from all of them (as a new tracer
    /// computes it, so a frame traces as a fresh tracer would).
    fn update_geometry(
        &mut self,
        triangles: &[GpuTriangle],
        changed: &[std::ops::Range<usize>],
    ) -> vk::Result<()> {
        if triangles.len() != self.triangle_count as usize
            || changed
                .iter()
                .any(|r| r.start > r.end || r.end > triangles.len())
        {
            return self.set_geometry(triangles);
        }
        self.gpu.wait_idle()?;
        for range in changed {
            self.triangles
                .write_at(range.start, &triangles[range.clone()])?;
        }
        (self.scene_min, self.scene_max, self.eps) = scene_box(triangles);
        Ok(())
    }

    fn trace(
        &mut self,
        rays: &Buffer,
        hits: &Buffer,
        ray_count: u32,
        query: Query,
        after: &[&TimelinePoint],
    ) -> vk::Result<TimelinePoint> {
        let _span = tracing::info_span!("pdacrt trace", rays = ray_count).entered();
        self.stats = TraceStats::default();
        // Everything below runs on the main stream after `after`.
        let rec = self.gpu.recorder(StreamKind::Main)?;
        rec.submit(after)?;
        let chunk = self.params.max_rays_per_chunk;
        let mut offset = 0;
        while offset < ray_count {
            let n = chunk.min(ray_count - offset);
            let chunk = Chunk {
                rays,
                hits,
                offset,
                n,
                query,
                index: self.stats.chunks,
            };
            self.trace_chunk(chunk)?;
            self.stats.chunks += 1;
            offset += n;
        }
        if !self.stats.levels.is_empty() {
            crate::timeline_counter!("pdacrt", "rays per level", 0);
        }
        self.gpu.recorder(StreamKind::Main)?.submit(&[])
    }
}
