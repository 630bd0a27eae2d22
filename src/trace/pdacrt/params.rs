//! PDACRT's parameters (paper §2.1–2.2), the variants of its steps, and their defaults
//! per device.

use serde::Serialize;

use super::types::MAX_IDS;
use crate::vk::{self, Gpu, LimitsInfo};

/// Shared memory per staged triangle in segmented_intersect.comp: the triangle (48
/// bytes) and its id.
pub const STAGED_TRIANGLE_BYTES: u64 = 52;
/// Shared memory per lane in filter_triangles.comp: its two children's boxes, four vec3s
/// at a 16-byte stride.
const LANE_BOUNDS_BYTES: u64 = 64;

/// The default [`PdacrtParams::terminal_cost_min_rays`]: on lavapipe the budget on
/// every level cost a 64² batch of `lamps`' path rays 1.3–1.6× its time (few nodes
/// per deep level), and from 2¹⁴ or 2¹⁶ ids on it cost nothing there and kept the
/// gain at 512².
const TERMINAL_COST_MIN_RAYS: u32 = 1 << 15;

/// How a level's lists are split into the children's lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum LevelSplit {
    /// The paper's way (§2.1, Figure 4): sort each list by status key (node << 2 |
    /// code), run-length encode the sorted keys into per-node, per-code counts, and
    /// read each child's range off the sorted list.
    SortByKey,
    /// Ranks by prefix sums of the side flags (left child: code left or both; right
    /// child: both or right). A list is already grouped by node, so the sort only ever
    /// reorders elements within a node; ranks on each side give each element its place
    /// within its child directly, and each child's size as a difference of two ranks.
    /// Same child lists (each in the parent list's order rather than code order, which
    /// no result depends on: ties go to the smaller triangle id), at the cost of one
    /// small scan instead of a multi-pass radix sort and a reduce-by-key per list.
    /// Lists are processed in tiles of one node (pdacrt.glsl): no per-id keys, the
    /// status code rides in the top two bits of each id, the filters count each tile's
    /// sides, one exclusive scan runs over the tile counts, and the scatter ranks the
    /// elements within their tile (tile_lanes.glsl).
    PrefixSums,
}

/// How a flush reduces its entries to each ray's closest hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum FlushReduce {
    /// The paper's way (Algorithm 3 lines 12–13): every (segment, ray) entry writes its
    /// closest hit; the entries are sorted by ray id, reduced by a segmented arg-min,
    /// and the runs update the global closest hits (Algorithm 1 line 9).
    SortByRay,
    /// Every entry lowers its ray's packed closest hit (ordered t, triangle; see
    /// pdacrt.glsl) with one 64-bit atomicMin — the arg-min's own order: t, then
    /// triangle index. No per-entry arrays, no sort, no sort scratch. Needs
    /// shaderBufferInt64Atomics.
    AtomicMin,
}

/// PDACRT's parameters (paper §2.1–2.2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PdacrtParams {
    /// α: a node with fewer triangles becomes terminal.
    pub alpha: u32,
    /// β: a node with fewer rays becomes terminal.
    pub beta: u32,
    /// η: capacity of the terminal-node buffer, in triangle ids and in ray ids.
    pub eta: u32,
    /// λ < η: the buffer is flushed when adding a level's terminal nodes would pass it.
    pub lambda: u32,
    /// T: triangles staged per shared-memory batch in the segmented intersection.
    pub batch: u32,
    /// N: invocations per workgroup (one terminal node each) in the segmented intersection.
    pub intersect_workgroup: u32,
    /// Invocations per workgroup (one tile each) of the filters and the scatter of
    /// [`LevelSplit::PrefixSums`].
    pub tile_workgroup: u32,
    /// Stage triangles through shared memory in batches of T (Algorithm 3 line 5), or
    /// read them straight from the triangle buffer (no barriers; for CPU devices).
    pub stage_triangles: bool,
    /// Rays traced per pass of the level loop; larger batches go in chunks.
    pub max_rays_per_chunk: u32,
    /// Deepest level; its surviving children are all terminal.
    pub max_depth: u32,
    /// How each level is split (Algorithm 2 lines 7–12).
    pub split: LevelSplit,
    /// How a flush finds each ray's closest hit (Algorithm 3 lines 12–13).
    pub flush_reduce: FlushReduce,
    /// A child's box: the bounds of its triangles (each clipped to the child's half of
    /// the parent's box), or the half itself as in the paper (Algorithm 2 line 4 splits
    /// the node's box; the children are its halves). Tight boxes shed the empty space
    /// around the geometry: rays that pass beside it leave the hierarchy a level
    /// after entering such a half instead of following it down, and the next split
    /// halves the geometry's extent rather than the empty space's. The bounds are one
    /// atomic min per coordinate per tile (filter_triangles.comp), order-independent,
    /// so the hierarchy and the hits stay deterministic.
    pub tight_boxes: bool,
    /// When few rays make a node terminal (the β test of Algorithm 1 line 6): 0, below
    /// β rays (the paper); else only while rays × triangles, the cost of its brute
    /// force, is also below this many tests. The paper's rule brute-forces a node of
    /// 200 rays and 20 000 triangles (4M tests) that a few more levels would cut to a
    /// few hundred thousand; but every level has a fixed cost (a dozen dispatches and
    /// a host round trip), which a budget too small spends on nodes of a few rays.
    pub terminal_cost: u32,
    /// The fewest ray ids a level must hold for [`Self::terminal_cost`] to apply in it;
    /// below, the paper's β test. A level's fixed cost is shared by its nodes: on a
    /// level of many rays the nodes the budget keeps in the loop ride along almost for
    /// free, while on a small batch's deep levels a few such nodes pay whole levels.
    pub terminal_cost_min_rays: u32,
    /// With [`LevelSplit::PrefixSums`], where a level's two scans (the tiles' side
    /// counts, the children's channels) hold at most
    /// [`SMALL_SCAN_MAX`](crate::primitives::scan::SMALL_SCAN_MAX) words each, one
    /// dispatch of one workgroup scans the side counts, makes the children, scans their
    /// channels and writes the totals (level_plan.comp) instead of four dispatches with
    /// barriers between them. The hierarchy and the hits are the same either way.
    pub one_dispatch_plan: bool,
}

impl Default for PdacrtParams {
    fn default() -> Self {
        Self {
            alpha: 256,
            beta: 256,
            eta: 1 << 19,
            lambda: 3 << 17,
            batch: 256,
            intersect_workgroup: 64,
            tile_workgroup: 64,
            stage_triangles: true,
            max_rays_per_chunk: 1 << 19,
            max_depth: 28,
            split: LevelSplit::SortByKey,
            flush_reduce: FlushReduce::SortByRay,
            tight_boxes: false,
            terminal_cost: 0,
            terminal_cost_min_rays: 0,
            one_dispatch_plan: true,
        }
    }
}

impl PdacrtParams {
    /// Defaults fitted to the device ([`Default`] is the paper's own setting).
    ///
    /// - Every device splits levels by prefix sums ([`LevelSplit::PrefixSums`]): one
    ///   scan does the work of a radix sort plus a reduce-by-key per list. On lavapipe
    ///   it cut the bunny's level time from 980 to 446 ms per 1024² frame
    ///   (docs/PERFORMANCE.md); on a GPU it is strictly fewer passes over the same data.
    /// - Devices with 64-bit buffer atomics reduce flushes atomically
    ///   ([`FlushReduce::AtomicMin`]): no sort by ray id, no per-entry arrays (bunny on
    ///   lavapipe: 1 224 → 1 006 ms per frame, back to back).
    /// - The paper's α = β = 256 and N = T = 256 are for a GTX 580; on CPU devices
    ///   (lavapipe) a sweep on the bunny (512², primary rays, docs/PERFORMANCE.md) found
    ///   α = 64 with β = 256 about 2× faster than 256/256: each level costs a fixed
    ///   handful of dispatches, while the segmented brute force is cheap per test, so
    ///   finer terminal nodes pay.
    /// - CPU devices read triangles directly in the segmented intersection instead of
    ///   staging them through shared memory: the barriers cost more than the staging
    ///   saves there (848 → 215 ms of intersection per bunny frame, docs/PERFORMANCE.md).
    /// - CPU devices halve the terminal-node buffer (η = 2¹⁸, λ = ¾η): its 4 MiB at the
    ///   paper-sized η were the difference between the bunny's 62.0 MiB peak and the
    ///   issue's 64 MB (61.0 MiB) target, and on lavapipe the more frequent flushes cost
    ///   nothing measurable (they clip rays to their hits sooner; docs/PERFORMANCE.md).
    ///   GPUs keep η = 2¹⁹: a flush there is one wide launch and should stay wide.
    /// - CPU devices give each tile one subgroup (lavapipe: 8 invocations) instead of 64
    ///   invocations: a workgroup wider than the SIMD width makes lavapipe switch
    ///   between its subgroups at every barrier, and the tile kernels have one or two.
    ///   On the bunny this halved the ray filter (188 → 98 ms per 1024² frame) and cut
    ///   the scatter from 108 to 58 ms (docs/PERFORMANCE.md). The segmented
    ///   intersection too runs one subgroup per segment there (N = 8 on lavapipe, so
    ///   segments of at most 64 rays): 212–219 → 172–187 ms per frame.
    /// - Every device boxes children by their triangles ([`Self::tight_boxes`]) and
    ///   keeps nodes of few rays but many triangles in the loop
    ///   ([`Self::terminal_cost`]): both only remove work (ray ids that leave sooner,
    ///   fewer intersection tests) for one fill and a few atomics per tile. On
    ///   lavapipe, 512² frames, together: the sea of `waves` 128–156 → 80–86 ms
    ///   (primary) and 92–94 → 61–65 ms (shadow), `swarm` 186–194 → 127–134 and 155 →
    ///   110–112, the bunny at 1024² 244–261 → 187–196 and 187–207 → 135–157
    ///   (docs/PERFORMANCE.md).
    /// - The batch must fit shared memory (`STAGED_TRIANGLE_BYTES` per staged triangle).
    pub fn for_device(gpu: &Gpu) -> Self {
        let mut p = Self::default();
        let shared = u64::from(gpu.info().limits.max_compute_shared_memory_size);
        p.batch = p.batch.min((shared / STAGED_TRIANGLE_BYTES) as u32);
        p.split = LevelSplit::PrefixSums;
        p.tight_boxes = true;
        p.terminal_cost_min_rays = TERMINAL_COST_MIN_RAYS;
        if gpu.info().capabilities.buffer_int64_atomics {
            p.flush_reduce = FlushReduce::AtomicMin;
        }
        if gpu.info().is_cpu() {
            p.alpha = 64;
            p.stage_triangles = false;
            p.eta = 1 << 18;
            p.lambda = 3 << 16;
            p.tile_workgroup = gpu.info().limits.subgroup_size.max(1);
            p.intersect_workgroup = p.tile_workgroup;
        } else {
            p.intersect_workgroup = 128;
        }
        // The cost rule's budget is α·β, the most a node below both thresholds costs
        // (larger budgets, 2¹⁶–2²⁰ tests on lavapipe, gave back most of the gain on the
        // sea's shadow rays: docs/PERFORMANCE.md).
        p.terminal_cost = p.alpha * p.beta;
        p
    }

    /// The budget of [`Self::terminal_cost`] on a level of `level_rays` ray ids (0: the
    /// paper's β test).
    pub fn terminal_cost_at(&self, level_rays: u32) -> u32 {
        if level_rays >= self.terminal_cost_min_rays {
            self.terminal_cost
        } else {
            0
        }
    }

    /// Whether a node of `tris` triangles and `rays` rays, on a level of `level_rays`
    /// ray ids, is terminal by its size (children.comp decides the same for every
    /// other node).
    pub fn is_terminal(&self, tris: u32, rays: u32, level_rays: u32) -> bool {
        let budget = self.terminal_cost_at(level_rays);
        let costly = budget != 0 && (rays as f32) * (tris as f32) >= budget as f32;
        tris < self.alpha || (rays < self.beta && !costly)
    }

    /// Rays per terminal segment at most: larger terminal nodes are split so that one
    /// node does not serialise on one workgroup (write_nodes.comp).
    pub fn max_segment_rays(&self) -> u32 {
        self.intersect_workgroup * 8
    }

    /// Refuses parameters no kernel can run with, or that the device with `limits`
    /// cannot (its workgroup invocations and shared memory); the message names each
    /// parameter by its `bench trace` option too.
    pub(super) fn validate(&self, limits: &LimitsInfo) -> vk::Result<()> {
        let bad = |what: &str| Err(vk::VkError::Usage(format!("PDACRT parameters: {what}")));
        if self.alpha == 0 || self.beta == 0 {
            return bad("α (--alpha) and β (--beta) must be at least 1");
        }
        if self.lambda == 0 || self.lambda > self.eta {
            return bad("λ (--lambda) must be in 1..=η (--eta)");
        }
        if self.batch == 0
            || self.intersect_workgroup == 0
            || self.tile_workgroup == 0
            || self.max_rays_per_chunk == 0
        {
            return bad(
                "T (--batch), N (--intersect-workgroup), --tile-workgroup and --chunk must be \
                 at least 1",
            );
        }
        if self.max_rays_per_chunk >= MAX_IDS {
            return bad("the chunk size (--chunk) must be below 2^30 rays");
        }
        // The tile workgroup shapes the kernels of the prefix-sum split alone.
        let tiles = self.split == LevelSplit::PrefixSums;
        let invocations = limits.max_compute_work_group_invocations;
        for (what, size) in [
            ("N (--intersect-workgroup)", self.intersect_workgroup),
            (
                "--tile-workgroup",
                if tiles { self.tile_workgroup } else { 1 },
            ),
        ] {
            if size > invocations {
                return bad(&format!(
                    "{what} {size} is more than the device's {invocations} invocations a workgroup"
                ));
            }
        }
        let shared = u64::from(limits.max_compute_shared_memory_size);
        let needs = [
            // filter_triangles.comp: each lane's two children's boxes.
            (
                u64::from(self.tile_workgroup) * LANE_BOUNDS_BYTES * u64::from(tiles),
                "--tile-workgroup",
                self.tile_workgroup,
            ),
            // segmented_intersect.comp: each staged triangle and its id.
            (
                u64::from(self.batch) * STAGED_TRIANGLE_BYTES * u64::from(self.stage_triangles),
                "T (--batch)",
                self.batch,
            ),
        ];
        for (bytes, what, value) in needs {
            if bytes > shared {
                return bad(&format!(
                    "{what} {value} needs {bytes} bytes of shared memory; the device has {shared}"
                ));
            }
        }
        Ok(())
    }
}
