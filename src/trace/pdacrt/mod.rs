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
//!   4). Rays passing beside the geometry leave a level later, and the next split
//!   halves the geometry rather than empty space.
//! - `cost_terminal`: a node below β rays stays in the loop while rays × triangles
//!   exceeds α·β (the default), or is terminal as in the paper (Algorithm 1 line 6),
//!   however many triangles it brute-forces.

mod kernels;
mod params;
mod pool;
pub mod types;

pub use self::params::{FlushReduce, LevelSplit, PdacrtParams};

use std::time::Instant;

use glam::Vec3;
use serde::Serialize;

use self::kernels::*;
use self::pool::BufferPool;
use self::types::{LevelTotals, Node, Segment, Tile, CHANNELS, CHILD_BYTES, MAX_IDS, TILE_ITEMS};
use super::{GpuTriangle, Hit, Query, Tracer};
use crate::primitives::{
    gather::Direction,
    reduce_by_key::{Reduction, RunOutputs},
    Gather, RadixSort, ReduceByKey, Scan, ScanKind, SortScratch, Tuning,
};
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

/// Level lists: the ids of each node's triangles and rays, with keys (node << 2 | code).
struct Level {
    nodes: Buffer,
    node_count: u32,
    tris: IdList,
    rays: IdList,
}

/// One of a level's two id lists and which node owns each id.
struct IdList {
    ids: Buffer,
    /// Per-id keys (node << 2 | code) when the level is split by sorting, `tiles` tiles
    /// (pdacrt.glsl) when by prefix sums.
    owner: Buffer,
    /// Tiles of the list (prefix-sum split; else 0).
    tiles: u32,
    /// Ids in the list.
    total: u32,
}

/// Which of a level's lists: names its buffers.
#[derive(Clone, Copy)]
enum ListKind {
    Triangles,
    Rays,
}

impl IdList {
    /// The buffers of a list of `total` ids, cut into `tiles` tiles when the level is
    /// split by prefix sums (`None`: per-id keys). `idle`: taken right after a host
    /// wait ([`BufferPool::take_while_idle`]).
    fn take(
        pool: &mut BufferPool,
        kind: ListKind,
        total: u32,
        tiles: Option<u32>,
        idle: bool,
    ) -> vk::Result<Self> {
        let (ids_name, owner_name) = match kind {
            ListKind::Triangles => ("pdacrt-tri-ids", "pdacrt-tri-owner"),
            ListKind::Rays => ("pdacrt-ray-ids", "pdacrt-ray-owner"),
        };
        let owner_bytes = tiles.map_or(total as u64 * 4, |t| t as u64 * size_of::<Tile>() as u64);
        let mut take = |name, bytes| {
            if idle {
                pool.take_while_idle(name, bytes)
            } else {
                pool.take(name, bytes)
            }
        };
        Ok(Self {
            ids: take(ids_name, total as u64 * 4)?,
            owner: take(owner_name, owner_bytes)?,
            tiles: tiles.unwrap_or(0),
            total,
        })
    }

    fn give(self, pool: &mut BufferPool) {
        pool.give(self.ids);
        pool.give(self.owner);
    }
}

/// The tiles of one node's `count` elements from `start` (pdacrt.glsl).
fn node_tiles(node: u32, start: u32, count: u32) -> impl Iterator<Item = Tile> {
    (0..count.div_ceil(TILE_ITEMS)).map(move |k| Tile {
        node,
        start: start + k * TILE_ITEMS,
        count: TILE_ITEMS.min(count - k * TILE_ITEMS),
        pad: 0,
    })
}

/// The side counts of a level split by prefix sums, per tile: four arrays (triangles
/// left and right, rays left and right) of tile count + 1 in one buffer, scanned
/// together into each tile's rank within its child.
struct Ranks {
    buffer: Buffer,
    tri_left: u32,
    tri_right: u32,
    ray_left: u32,
    ray_right: u32,
}

impl Ranks {
    /// Where the (left, right) arrays of the triangle and of the ray list start; zeros
    /// when the level is split by sorting (the kernels then ignore them).
    fn bases(ranks: Option<&Ranks>) -> ((u32, u32), (u32, u32)) {
        ranks.map_or(((0, 0), (0, 0)), |r| {
            ((r.tri_left, r.tri_right), (r.ray_left, r.ray_right))
        })
    }

    /// Words in all four arrays.
    fn len(&self) -> u32 {
        2 * self.tri_right + 2 * (self.ray_right - self.ray_left)
    }
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
}

/// What filtering a level leaves for building the next one.
struct Filtered {
    totals: LevelTotals,
    /// Per-child records (children.comp).
    children: Buffer,
    /// The prefix-summed channels, `stride` words each.
    offsets: Buffer,
    stride: u32,
    ranks: Option<Ranks>,
}

/// The terminal-node buffer and its fill.
struct TerminalBuffer {
    tri_ids: Buffer,
    ray_ids: Buffer,
    segments: Buffer,
    tri_capacity: u32,
    ray_capacity: u32,
    segment_capacity: u32,
    tris: u32,
    rays: u32,
    segment_count: u32,
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

/// The box around the triangles (as the GPU reconstructs their vertices) and the padding
/// of every box test: 1e-5 of the larger of the scene's extent and its distance from the
/// origin, well above float rounding of coordinates that size.
fn scene_box(triangles: &[GpuTriangle]) -> (Vec3, Vec3, f32) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for t in triangles {
        for p in [t.v0(), t.v0() + t.e1(), t.v0() + t.e2()] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
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
        params.validate()?;
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

    /// A terminal-node buffer for `tri_capacity` triangle ids, `ray_capacity` ray ids and
    /// `segment_capacity` segments (at least 1024).
    fn new_terminal_buffer(
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
        })
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
    fn trace_chunk(&mut self, chunk: Chunk<'_>, index: u32) -> vk::Result<()> {
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
        // Levels split by prefix sums are cut into tiles; sorted ones carry per-id keys.
        let tiled = p.split == LevelSplit::PrefixSums;
        let tris = self.triangle_count;
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

        // Algorithm 1 line 2: the root level. A root already below α or β is terminal.
        let mut level = if tris == 0 {
            None // every ray misses
        } else if p.is_terminal(tris, n) {
            let per = p.max_segment_rays();
            let segment_count = n.div_ceil(per);
            if tris > term.tri_capacity
                || n > term.ray_capacity
                || segment_count > term.segment_capacity
            {
                let bigger = self.new_terminal_buffer(
                    tris.max(term.tri_capacity),
                    n.max(term.ray_capacity),
                    segment_count.max(term.segment_capacity),
                )?;
                let old = std::mem::replace(&mut term, bigger);
                self.give_terminal(old);
            }
            let seg_tags = self.pool.take("pdacrt-tags", tris.max(n) as u64 * 4)?;
            self.iota(&mut rec, &term.tri_ids, &seg_tags, tris, 0, 0)?;
            self.iota(&mut rec, &term.ray_ids, &seg_tags, n, 0, 0)?;
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
            None
        } else {
            let pool = &mut self.pool;
            let tiles = |count: u32| tiled.then(|| count.div_ceil(TILE_ITEMS));
            let level = Level {
                nodes: pool.take("pdacrt-nodes", size_of::<Node>() as u64)?,
                node_count: 1,
                tris: IdList::take(pool, ListKind::Triangles, tris, tiles(tris), false)?,
                rays: IdList::take(pool, ListKind::Rays, n, tiles(n), false)?,
            };
            rec.update(&level.nodes, 0, &[root])?;
            for (ids, owner, count) in [
                (&level.tris.ids, &level.tris.owner, tris),
                (&level.rays.ids, &level.rays.owner, n),
            ] {
                if tiled {
                    self.iota_ids(&mut rec, ids, count)?;
                    let tiles: Vec<Tile> = node_tiles(0, 0, count).collect();
                    // vkCmdUpdateBuffer takes at most 64 KiB at a time.
                    for (i, part) in tiles.chunks(4096).enumerate() {
                        rec.update(owner, (i * 4096 * size_of::<Tile>()) as u64, part)?;
                    }
                } else {
                    self.iota(&mut rec, ids, owner, count, 0, 0)?;
                }
            }
            rec.barrier();
            Some(level)
        };
        rec.submit(&[])?;

        let mut depth = 0u32;
        while let Some(current) = level.take() {
            let started = Instant::now();
            let Filtered {
                totals,
                children,
                offsets,
                stride,
                ranks,
            } = self.filter_level(&current, &chunk, depth)?;
            self.stats.host_round_trips += 1;

            // Lines 11–15 (recorded below): the next level's lists. Taken while nothing is
            // in flight (filter_level waited), so the buffers the pool lets go to make room
            // go at once instead of at the next wait, and whatever stays free after these
            // takes is freed too (the next level allocates what it misses): peak memory.
            let next = (totals.next_nodes > 0)
                .then(|| -> vk::Result<Level> {
                    // Largest first (see take_while_idle).
                    let pool = &mut self.pool;
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
                    })
                })
                .transpose()?;
            let child_count = current.node_count * 2;
            let routes = self
                .pool
                .take_while_idle("pdacrt-routes", child_count as u64 * 16)?;
            self.pool.clear(); // only free buffers: the taken ones are not in the pool

            // Algorithm 1 lines 7–10: flush first if this level's terminal nodes would
            // push the buffer past λ.
            let flushed = term.tris + totals.term_tris > p.lambda
                || term.rays + totals.term_rays > p.lambda
                || term.segment_count + totals.term_nodes > term.segment_capacity;
            if flushed && term.segment_count > 0 {
                self.flush(&mut term, &chunk)?;
            }
            if totals.term_tris > term.tri_capacity
                || totals.term_rays > term.ray_capacity
                || totals.term_nodes > term.segment_capacity
            {
                // One level alone exceeds η: grow the (now empty) buffer to fit it.
                let bigger = self.new_terminal_buffer(
                    totals.term_tris.max(term.tri_capacity),
                    totals.term_rays.max(term.ray_capacity),
                    totals.term_nodes.max(term.segment_capacity),
                )?;
                let old = std::mem::replace(&mut term, bigger);
                self.give_terminal(old);
            }

            let mut rec = gpu.recorder(StreamKind::Main)?;
            let empty = &term.segments; // bound where a list is empty; never written then
            let (next_nodes, next_tri_ids, next_tri_owner, next_ray_ids, next_ray_owner) =
                match &next {
                    Some(l) => (
                        &l.nodes,
                        &l.tris.ids,
                        &l.tris.owner,
                        &l.rays.ids,
                        &l.rays.owner,
                    ),
                    None => (empty, empty, empty, empty, empty),
                };
            let mut bindings: Vec<BufferSlice> = vec![
                (&children).into(),
                (&offsets).into(),
                next_nodes.into(),
                (&term.segments).into(),
                (&routes).into(),
            ];
            if tiled {
                // The next level's tiles (its keys are written by the scatter instead).
                bindings.extend([
                    BufferSlice::from(next_tri_owner),
                    BufferSlice::from(next_ray_owner),
                ]);
            }
            rec.dispatch_items(
                &self.kernels.write_nodes,
                &bindings,
                &WriteNodesPush {
                    child_count,
                    stride,
                    segment_base: term.segment_count,
                    term_tri_base: term.tris,
                    term_ray_base: term.rays,
                    max_segment_rays: p.max_segment_rays(),
                    tile_items: TILE_ITEMS,
                },
                child_count as u64,
            )?;
            rec.barrier();
            let (tri_sides, ray_sides) = Ranks::bases(ranks.as_ref());
            for (rays_list, list, next_ids, next_owner, term_ids, sides) in [
                (
                    0,
                    &current.tris,
                    next_tri_ids,
                    next_tri_owner,
                    &term.tri_ids,
                    tri_sides,
                ),
                (
                    1,
                    &current.rays,
                    next_ray_ids,
                    next_ray_owner,
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
                match &ranks {
                    // One workgroup per tile.
                    Some(ranks) => rec.dispatch(
                        &self.kernels.scatter,
                        &[
                            (&list.owner).into(),
                            (&list.ids).into(),
                            (&routes).into(),
                            next_ids.into(),
                            term_ids.into(),
                            (&ranks.buffer).into(),
                        ],
                        &push,
                        grid_for(&gpu, list.tiles as u64, 1),
                    )?,
                    None => rec.dispatch_items(
                        &self.kernels.scatter,
                        &[
                            (&list.owner).into(),
                            (&list.ids).into(),
                            (&routes).into(),
                            next_ids.into(),
                            next_owner.into(),
                            term_ids.into(),
                        ],
                        &push,
                        list.total as u64,
                    )?,
                }
            }
            rec.barrier();
            rec.submit(&[])?;
            term.tris += totals.term_tris;
            term.rays += totals.term_rays;
            term.segment_count += totals.term_nodes;

            crate::timeline_counter!("pdacrt", "rays per level", current.rays.total);
            self.stats.levels.push(LevelStats {
                chunk: index,
                level: depth,
                nodes: current.node_count,
                triangles: current.tris.total,
                rays: current.rays.total,
                ray_duplication: current.rays.total as f64 / n.max(1) as f64,
                terminal_nodes: totals.term_nodes,
                flushed,
                ms: started.elapsed().as_secs_f64() * 1e3,
            });
            // Line 16: the current level's lists go back to the pool.
            current.tris.give(&mut self.pool);
            current.rays.give(&mut self.pool);
            for b in [current.nodes, children, offsets, routes] {
                self.pool.give(b);
            }
            if let Some(ranks) = ranks {
                self.pool.give(ranks.buffer);
            }
            level = next;
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

    fn give_terminal(&mut self, term: TerminalBuffer) {
        self.pool.give(term.tri_ids);
        self.pool.give(term.ray_ids);
        self.pool.give(term.segments);
    }

    /// Filters one level (Algorithm 1 lines 4–6, Algorithm 2) and reads its totals back:
    /// the loop's one host round trip per level.
    fn filter_level(
        &mut self,
        level: &Level,
        chunk: &Chunk<'_>,
        depth: u32,
    ) -> vk::Result<Filtered> {
        let &Chunk {
            rays,
            hits,
            offset: ray_offset,
            query,
            ..
        } = chunk;
        let gpu = self.gpu.clone();
        let max_list = level.tris.total.max(level.rays.total);
        let child_count = level.node_count * 2;
        // Channel stride: a multiple of 64 words keeps every channel slice aligned.
        let stride = child_count.next_multiple_of(64);
        let ranked = self.params.split == LevelSplit::PrefixSums;
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
        let scan_n = ranks.as_ref().map_or(0, Ranks::len);
        if !ranked {
            self.sort_scratch(max_list)?;
        }
        let scanned = if ranked { scan_n } else { max_list };
        self.misc_scratch(scanned.max(CHANNELS * stride), !ranked)?;
        let children = self
            .pool
            .take("pdacrt-children", child_count as u64 * CHILD_BYTES)?;
        let channels = self
            .pool
            .take("pdacrt-channels", (stride * CHANNELS) as u64 * 4)?;
        let offsets = self
            .pool
            .take("pdacrt-offsets", (stride * CHANNELS) as u64 * 4)?;
        let summary = gpu.create_buffer(
            "pdacrt-level-totals",
            size_of::<LevelTotals>() as u64,
            MemoryKind::Readback,
        )?;
        // The children's triangle bounds (tight boxes; filter_triangles.comp), 8 words
        // per child, all ones for "none yet". Without tight boxes the kernels never
        // touch it: one word stands in.
        let tight = self.params.tight_boxes;
        let bounds_bytes = if tight { child_count as u64 * 32 } else { 4 };
        let bounds = self.pool.take("pdacrt-bounds", bounds_bytes)?;

        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.begin_scope("pdacrt-level")?;
        if tight {
            rec.fill_range(&bounds, 0, bounds_bytes, u32::MAX)?;
            rec.barrier();
        }
        // Algorithm 2 lines 2–6: status codes (and, ranked, the side flags).
        let (tri_bases, ray_bases) = Ranks::bases(ranks.as_ref());
        let mut bindings: Vec<BufferSlice> = vec![
            (&self.triangles).into(),
            (&level.nodes).into(),
            (&level.tris.ids).into(),
            (&level.tris.owner).into(),
        ];
        bindings.extend(ranks.as_ref().map(|r| BufferSlice::from(&r.buffer)));
        bindings.push((&bounds).into());
        // Ranked: one workgroup per tile; sorted: one invocation per id.
        let groups = |items: u32, tiles: u32, pipeline: &vk::ComputePipeline| {
            if ranked {
                grid_for(&gpu, tiles as u64, 1)
            } else {
                grid_for(&gpu, items as u64, pipeline.workgroup_size())
            }
        };
        rec.dispatch(
            &self.kernels.filter_triangles,
            &bindings,
            &FilterTrianglesPush {
                n: if ranked {
                    level.tris.tiles
                } else {
                    level.tris.total
                },
                eps: self.eps,
                left_base: tri_bases.0,
                right_base: tri_bases.1,
                tight: tight as u32,
            },
            groups(
                level.tris.total,
                level.tris.tiles,
                &self.kernels.filter_triangles,
            ),
        )?;
        let mut bindings: Vec<BufferSlice> = vec![
            rays.into(),
            (&level.nodes).into(),
            (&level.rays.ids).into(),
            (&level.rays.owner).into(),
            hits.into(),
        ];
        bindings.extend(ranks.as_ref().map(|r| BufferSlice::from(&r.buffer)));
        rec.dispatch(
            &self.kernels.filter_rays,
            &bindings,
            &FilterRaysPush {
                n: if ranked {
                    level.rays.tiles
                } else {
                    level.rays.total
                },
                eps: self.eps,
                occlusion: (query == Query::Occlusion) as u32,
                ray_offset,
                left_base: ray_bases.0,
                right_base: ray_bases.1,
            },
            groups(
                level.rays.total,
                level.rays.tiles,
                &self.kernels.filter_rays,
            ),
        )?;
        let min_extent = self.eps * 4.0;
        let push = ChildrenPush {
            child_count,
            stride,
            alpha: self.params.alpha,
            beta: self.params.beta,
            last_level: (depth + 1 >= self.params.max_depth) as u32,
            min_extent,
            max_segment_rays: self.params.max_segment_rays(),
            tile_items: TILE_ITEMS,
            tri_left_base: tri_bases.0,
            tri_right_base: tri_bases.1,
            ray_left_base: ray_bases.0,
            ray_right_base: ray_bases.1,
            tight: tight as u32,
            cost_rule: self.params.cost_terminal as u32,
        };
        let counts = match &ranks {
            Some(ranks) => {
                rec.barrier();
                // Every tile-count array in one exclusive scan: each array's ranks come
                // out offset by the arrays before it, which cancels in every use (a
                // child's size and an element's offset are differences of ranks).
                let misc = self.scratch.misc.as_ref().unwrap();
                let all = (&ranks.buffer).into();
                self.scan
                    .record(&mut rec, scan_n, all, all, ScanKind::Exclusive, misc)?;
                // Algorithm 2 lines 13–15 and Algorithm 1 line 6.
                rec.dispatch_items(
                    &self.kernels.children,
                    &[
                        (&level.nodes).into(),
                        (&ranks.buffer).into(),
                        (&children).into(),
                        (&channels).into(),
                        (&bounds).into(),
                    ],
                    &push,
                    child_count as u64,
                )?;
                None
            }
            None => {
                let counts = self.record_sort_split(&mut rec, level)?;
                rec.dispatch_items(
                    &self.kernels.children,
                    &[
                        (&level.nodes).into(),
                        (&counts.0).into(),
                        (&counts.1).into(),
                        (&children).into(),
                        (&channels).into(),
                        (&bounds).into(),
                    ],
                    &push,
                    child_count as u64,
                )?;
                Some(counts)
            }
        };
        rec.barrier();
        // Algorithm 1 line 11: positions of the next level and of the terminal nodes.
        // One scan runs through all the channels back to back; each channel's offsets
        // come out raised by the channels before it (and by the unwritten padding up to
        // `stride`), which the readers subtract (channel_offset in pdacrt.glsl).
        let misc = self.scratch.misc.as_ref().unwrap();
        self.scan.record(
            &mut rec,
            CHANNELS * stride,
            (&channels).into(),
            (&offsets).into(),
            ScanKind::Exclusive,
            misc,
        )?;
        rec.dispatch(
            &self.kernels.level_summary,
            &[(&channels).into(), (&offsets).into(), (&summary).into()],
            &SummaryPush {
                child_count,
                stride,
            },
            [1, 1, 1],
        )?;
        rec.end_scope()?;
        let done = rec.submit(&[])?;
        gpu.wait(&done)?;
        self.scratch.retired.clear();
        self.pool.collect();
        let totals = summary.read::<LevelTotals>()?[0];
        self.pool.give(channels);
        self.pool.give(bounds);
        if let Some((tri_counts, ray_counts)) = counts {
            self.pool.give(tri_counts);
            self.pool.give(ray_counts);
        }
        Ok(Filtered {
            totals,
            children,
            offsets,
            stride,
            ranks,
        })
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

    /// Processes the terminal-node buffer (Algorithm 3) and updates the global closest
    /// hits (Algorithm 1 line 9). Recorded without a host wait.
    fn flush(&mut self, term: &mut TerminalBuffer, chunk: &Chunk<'_>) -> vk::Result<()> {
        let gpu = self.gpu.clone();
        let entries = term.rays;
        self.stats.flushes += 1;
        if self.params.flush_reduce == FlushReduce::AtomicMin {
            return self.flush_atomic(term, chunk);
        }
        let &Chunk {
            offset: ray_offset,
            n: chunk_rays,
            hits,
            ..
        } = chunk;
        self.sort_scratch(entries)?;
        self.misc_scratch(entries, true)?;
        let entry_t = self.pool.take("pdacrt-entry-t", entries as u64 * 4)?;
        let entry_tri = self.pool.take("pdacrt-entry-tri", entries as u64 * 4)?;
        let keys = self.pool.take("pdacrt-entry-rays", entries as u64 * 4)?;
        let order = self.pool.take("pdacrt-entry-order", entries as u64 * 4)?;
        let sorted_t = self.pool.take("pdacrt-sorted-t", entries as u64 * 4)?;
        let sorted_tri = self.pool.take("pdacrt-sorted-tri", entries as u64 * 4)?;
        let run_total = self.pool.take("pdacrt-run-total", 4)?;
        let (_, sort_scratch) = self.scratch.sort.as_ref().unwrap();
        let misc = self.scratch.misc.as_ref().unwrap();

        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.begin_scope("pdacrt-flush")?;
        // Algorithm 3 lines 2–10.
        self.record_segmented_intersect(
            &mut rec,
            term,
            chunk,
            &[(&entry_t).into(), (&entry_tri).into()],
        )?;
        // Lines 12–13: sort the entries by ray id, then the segmented arg-min.
        rec.copy(&term.ray_ids, 0, &keys, 0, entries as u64 * 4);
        rec.dispatch_items(
            &self.kernels.iota,
            &[(&order).into(), (&sorted_t).into()],
            &IotaPush {
                n: entries,
                base: 0,
                tag: 0,
            },
            entries as u64,
        )?;
        rec.barrier();
        self.sort.record(
            &mut rec,
            entries,
            (&keys).into(),
            Some((&order).into()),
            0..bits_for(chunk_rays),
            sort_scratch,
        )?;
        for (src, out) in [(&entry_t, &sorted_t), (&entry_tri, &sorted_tri)] {
            self.gather.record(
                &mut rec,
                entries,
                Direction::Gather,
                src.into(),
                (&order).into(),
                out.into(),
                misc,
            )?;
        }
        self.reduce.record(
            &mut rec,
            entries,
            (&keys).into(),
            Reduction::ArgMin {
                t: (&sorted_t).into(),
                ids: (&sorted_tri).into(),
            },
            // The per-entry arrays are dead once gathered into sorted order: the runs
            // (at most one per entry) reuse them, which keeps a flush at six arrays.
            RunOutputs {
                keys: (&order).into(),
                a: (&entry_t).into(),
                b: Some((&entry_tri).into()),
                count: (&run_total).into(),
            },
            misc,
        )?;
        // Algorithm 1 line 9.
        rec.dispatch_items(
            &self.kernels.update_hits,
            &[
                (&order).into(),
                (&entry_t).into(),
                (&entry_tri).into(),
                (&run_total).into(),
                hits.into(),
            ],
            &UpdateHitsPush {
                max_runs: entries,
                ray_offset,
            },
            entries as u64,
        )?;
        rec.barrier();
        rec.end_scope()?;
        rec.submit(&[])?;
        for b in [
            entry_t, entry_tri, keys, order, sorted_t, sorted_tri, run_total,
        ] {
            self.pool.give(b);
        }
        term.tris = 0;
        term.rays = 0;
        term.segment_count = 0;
        Ok(())
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
        term.tris = 0;
        term.rays = 0;
        term.segment_count = 0;
        Ok(())
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
            };
            self.trace_chunk(chunk, self.stats.chunks)?;
            self.stats.chunks += 1;
            offset += n;
        }
        if !self.stats.levels.is_empty() {
            crate::timeline_counter!("pdacrt", "rays per level", 0);
        }
        self.gpu.recorder(StreamKind::Main)?.submit(&[])
    }
}
