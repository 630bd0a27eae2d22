//! Serial CPU divide-and-conquer ray tracing (DACRT) after Mora 2011, "Naive ray-tracing:
//! a divide-and-conquer approach" — the serial baseline that PDACRT is compared with.
//!
//! The structure follows Algorithm 2 ("Serial DACRT") of the 2015 thesis *Two GPU
//! algorithms for raytracing* (/work/shared/papers), line by line:
//!
//! ```text
//!  1: procedure DACRT(Space E, SetOfRays R, SetOfPrimitives P)
//!  3:   if R.size() < rLimit or P.size() < pLimit then NaiveRT(R, P)
//!  4:   else
//!  5:     E_i = SubdivideSpace(E)
//!  6:     for each E_i do
//!  7:       SetOfRays R' = R ∩ E_i
//!  8:       SetOfPrimitives P' = P ∩ E_i
//!  9:       DACRT(E_i, R', P')
//! ```
//!
//! There is no tree: a node is a box plus a prefix of the ray-index list and a prefix of
//! the triangle-index list. Lines 7–8 are in-place partitions of the parent's lists
//! moving the elements that overlap child E_i to the front (the "pivots" of Mora and of
//! the thesis, figure 2.1); the child recurses on that prefix, which it may permute but
//! never leaves, so the next child can partition the parent's lists again.
//!
//! Choices the pseudo-code leaves open:
//! - SubdivideSpace (line 5) splits at the midpoint of the box's largest extent, as PDACRT
//!   does, so the two tracers build the same implicit k-d tree.
//! - rLimit/pLimit are [`DacrtParams::leaf_rays`] (β) and [`DacrtParams::leaf_triangles`]
//!   (α). PDACRT uses α = β = 256 to fill GPU blocks; neither the thesis nor this crate
//!   has Mora's exact values, and a serial CPU traversal wants small leaves: on the bunny
//!   at 512×512 (`bunny_dacrt_threshold_sweep` in tests/suite/trace_tracers.rs) throughput is
//!   flat within noise for α in 8..64 and β in 4..32, and drops by a third at 256/256;
//!   the defaults α = 16, β = 8 sit in the middle of that plateau. Boxes that can no longer be
//!   split, and nodes deeper than [`DacrtParams::max_depth`], are also intersected
//!   naively, so many triangles sharing one point cannot recurse forever.
//! - Ray filtering (line 7) clips each ray's live segment [tmin, min(tmax, closest t so
//!   far)] against the child box, so rays that already hit something nearer never enter
//!   a farther box (Mora's early ray termination). Children are visited near-to-far per
//!   ray group, as Mora does: the node's rays are first partitioned by the sign of their
//!   direction along the split axis; the positive group visits left then right, the
//!   negative group right then left. In occlusion mode a ray leaves every list at its
//!   first hit.
//! - Mora's conic packets and SIMD filtering are not implemented: this is the plain
//!   algorithm, single threaded.
//!
//! Exactness: leaves use [`cpu::intersect_triangle`], and a ray keeps the lexicographic
//! minimum (t, triangle index) of every triangle it meets, so a triangle met twice (it
//! straddles a split and sits in both children) or met in a later leaf at the same t
//! still resolves to the smaller index: the result is bit-identical to
//! [`cpu::closest_hits`]. The box tests are conservative (boxes padded by a small
//! fraction of the scene size, segments by a relative margin): extra rays in a node cost
//! time, never correctness.

use std::time::Duration;

use glam::Vec3;

use super::{cpu, trace_on_host, GpuTriangle, Hit, Query, Ray, Tracer, MISS};
use crate::vk::{self, Buffer, Gpu, TimelinePoint};

/// Thresholds of the recursion (Algorithm 2, line 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DacrtParams {
    /// α (pLimit): a node with fewer triangles is intersected naively.
    pub leaf_triangles: u32,
    /// β (rLimit): a node with fewer rays is intersected naively.
    pub leaf_rays: u32,
    /// Nodes this deep are intersected naively whatever their sizes.
    pub max_depth: u32,
}

impl Default for DacrtParams {
    fn default() -> Self {
        Self {
            leaf_triangles: 16,
            leaf_rays: 8,
            max_depth: 48,
        }
    }
}

/// What one traversal did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DacrtStats {
    /// Nodes visited (interior and leaves), counting a node once per ray group.
    pub nodes: u64,
    /// Naive leaves.
    pub leaves: u64,
    /// Ray–triangle tests in the leaves.
    pub ray_triangle_tests: u64,
    pub max_depth: u32,
}

#[derive(Clone, Copy, Debug)]
struct Aabb {
    lo: Vec3,
    hi: Vec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: Vec3::INFINITY,
        hi: Vec3::NEG_INFINITY,
    };

    fn of_triangle(t: &GpuTriangle) -> Aabb {
        let (lo, hi) = t.bounds();
        Aabb { lo, hi }
    }

    fn union(self, o: Aabb) -> Aabb {
        Aabb {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }
}

/// A ray as the traversal uses it.
struct RayData {
    o: Vec3,
    d: Vec3,
    inv: Vec3,
    tmin: f32,
    tmax: f32,
    /// Margin added to both ends of a clipped segment, in units of t.
    t_pad: f32,
}

struct Dacrt<'a> {
    triangles: &'a [GpuTriangle],
    tri_boxes: Vec<Aabb>,
    rays: Vec<RayData>,
    hits: Vec<Hit>,
    /// Occlusion mode: the ray has found a blocker and takes no further part.
    done: Vec<bool>,
    occlusion: bool,
    params: DacrtParams,
    /// Spatial padding of every box test.
    pad: f32,
    stats: DacrtStats,
}

/// Moves the elements satisfying `keep` to the front, returns how many there are: the
/// pivot of a child's list (Algorithm 2, lines 7 and 8).
fn partition(list: &mut [u32], mut keep: impl FnMut(u32) -> bool) -> usize {
    let mut pivot = 0;
    for i in 0..list.len() {
        if keep(list[i]) {
            list.swap(i, pivot);
            pivot += 1;
        }
    }
    pivot
}

impl Dacrt<'_> {
    /// Whether ray `r`'s live segment [tmin, min(tmax, closest t)] meets `b` (padded).
    fn ray_enters(&self, r: u32, b: &Aabb) -> bool {
        let r = r as usize;
        if self.done[r] {
            return false;
        }
        let ray = &self.rays[r];
        let best = self.hits[r].t;
        let mut t0 = ray.tmin;
        let mut t1 = ray.tmax.min(best);
        let (lo, hi) = (b.lo - self.pad, b.hi + self.pad);
        for a in 0..3 {
            if ray.d[a] == 0.0 {
                // Parallel to the slab: inside it or never.
                if !(ray.o[a] >= lo[a] && ray.o[a] <= hi[a]) {
                    return false;
                }
                continue;
            }
            let ta = (lo[a] - ray.o[a]) * ray.inv[a];
            let tb = (hi[a] - ray.o[a]) * ray.inv[a];
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        // Relative and absolute margins: rounding in the slabs and in t never hides a
        // box the segment touches.
        t0 - ray.t_pad - 1e-5 * t0.abs() <= t1 + ray.t_pad + 1e-5 * t1.abs()
    }

    /// Whether triangle `t` overlaps box `b` along `axis` (it overlaps the parent, which
    /// differs from `b` along the split axis only).
    fn triangle_overlaps(&self, t: u32, b: &Aabb, axis: usize) -> bool {
        let tb = &self.tri_boxes[t as usize];
        tb.lo[axis] <= b.hi[axis] + self.pad && tb.hi[axis] >= b.lo[axis] - self.pad
    }

    /// NaiveRT(R, P) (Algorithm 2, line 3): every live ray against every triangle,
    /// keeping the lexicographic minimum (t, index).
    fn naive(&mut self, rays: &[u32], tris: &[u32]) {
        self.stats.leaves += 1;
        for &r in rays {
            let r = r as usize;
            if self.done[r] {
                continue;
            }
            let ray = &self.rays[r];
            let sheared = cpu::ShearedRay::new(ray.o, ray.d);
            let mut best = self.hits[r];
            let mut tests = 0u64;
            for &t in tris {
                tests += 1;
                let (th, u, v) = sheared.intersect(ray.tmin, ray.tmax, &self.triangles[t as usize]);
                if th < best.t || (th == best.t && th.is_finite() && t < best.triangle) {
                    best = Hit {
                        t: th,
                        triangle: t,
                        u,
                        v,
                    };
                    if self.occlusion {
                        self.done[r] = true;
                        break;
                    }
                }
            }
            self.stats.ray_triangle_tests += tests;
            self.hits[r] = best;
        }
    }

    /// DACRT(E, R, P) (Algorithm 2, line 1): `rays` and `tris` are already the node's.
    fn node(&mut self, e: Aabb, rays: &mut [u32], tris: &mut [u32], depth: u32) {
        self.stats.nodes += 1;
        self.stats.max_depth = self.stats.max_depth.max(depth);
        if rays.is_empty() || tris.is_empty() {
            return;
        }
        // Line 5: SubdivideSpace — the midpoint of the largest extent.
        let extent = e.hi - e.lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = 0.5 * (e.lo[axis] + e.hi[axis]);
        let splittable = mid > e.lo[axis] && mid < e.hi[axis];
        // Line 3: small enough (or no longer divisible) → NaiveRT.
        if (rays.len() as u64) < self.params.leaf_rays as u64
            || (tris.len() as u64) < self.params.leaf_triangles as u64
            || depth >= self.params.max_depth
            || !splittable
        {
            self.naive(rays, tris);
            return;
        }
        let mut left = e;
        left.hi[axis] = mid;
        let mut right = e;
        right.lo[axis] = mid;
        // Near-to-far per ray group: rays heading +axis meet the left child first.
        let positive = partition(rays, |r| self.rays[r as usize].d[axis] >= 0.0);
        let (pos, neg) = rays.split_at_mut(positive);
        for (group, order) in [(pos, [left, right]), (neg, [right, left])] {
            // Line 6: for each E_i.
            for child in order {
                if group.is_empty() {
                    break;
                }
                // Line 7: R' = R ∩ E_i (live segments only).
                let r_pivot = partition(group, |r| self.ray_enters(r, &child));
                if r_pivot == 0 {
                    continue;
                }
                // Line 8: P' = P ∩ E_i.
                let t_pivot = partition(tris, |t| self.triangle_overlaps(t, &child, axis));
                // Line 9: DACRT(E_i, R', P').
                self.node(
                    child,
                    &mut group[..r_pivot],
                    &mut tris[..t_pivot],
                    depth + 1,
                );
            }
        }
    }
}

/// Traces `rays` against `triangles` with serial DACRT. Closest hits are bit-identical
/// to [`cpu::closest_hits`]; in occlusion mode a hit is any blocker.
pub fn trace(
    rays: &[Ray],
    triangles: &[GpuTriangle],
    query: Query,
    params: &DacrtParams,
) -> (Vec<Hit>, DacrtStats) {
    let mut hits = vec![Hit::NONE; rays.len()];
    if rays.is_empty() || triangles.is_empty() {
        return (hits, DacrtStats::default());
    }
    let tri_boxes: Vec<Aabb> = triangles.iter().map(Aabb::of_triangle).collect();
    let scene = tri_boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
    // Padding: a small fraction of the scene size, plus a few ulps of its coordinates.
    let size = (scene.hi - scene.lo).max_element();
    let magnitude = scene.lo.abs().max(scene.hi.abs()).max_element();
    let pad = if size.is_finite() && magnitude.is_finite() {
        1e-5 * size + 1e-6 * magnitude + f32::MIN_POSITIVE
    } else {
        0.0
    };
    let ray_data: Vec<RayData> = rays
        .iter()
        .map(|r| {
            let d = Vec3::from(r.dir);
            let len = d.length();
            RayData {
                o: Vec3::from(r.origin),
                d,
                inv: d.recip(),
                tmin: r.tmin,
                tmax: r.tmax,
                t_pad: if len > 0.0 { pad / len } else { 0.0 },
            }
        })
        .collect();
    let mut dacrt = Dacrt {
        triangles,
        tri_boxes,
        rays: ray_data,
        hits: std::mem::take(&mut hits),
        done: vec![false; rays.len()],
        occlusion: query == Query::Occlusion,
        params: *params,
        pad,
        stats: DacrtStats::default(),
    };
    // The root node: rays whose segment is not empty (tmax > tmin, as for every tracer)
    // and meets the scene box, every triangle.
    let mut ray_list: Vec<u32> = (0..rays.len() as u32).collect();
    let live = partition(&mut ray_list, |r| {
        !rays[r as usize].is_empty() && dacrt.ray_enters(r, &scene)
    });
    let mut tri_list: Vec<u32> = (0..triangles.len() as u32).collect();
    dacrt.node(scene, &mut ray_list[..live], &mut tri_list, 0);
    debug_assert!(dacrt
        .hits
        .iter()
        .all(|h| h.t.is_finite() == (h.triangle != MISS)));
    (dacrt.hits, dacrt.stats)
}

/// The serial CPU DACRT as a [`Tracer`]: reads the rays back from the GPU, traces on one
/// CPU thread, writes the hits.
pub struct CpuDacrtTracer {
    gpu: Gpu,
    triangles: Vec<GpuTriangle>,
    params: DacrtParams,
    last_stats: DacrtStats,
    last_time: Duration,
}

impl CpuDacrtTracer {
    pub fn new(gpu: &Gpu, triangles: &[GpuTriangle]) -> Self {
        Self::with_params(gpu, triangles, DacrtParams::default())
    }

    pub fn with_params(gpu: &Gpu, triangles: &[GpuTriangle], params: DacrtParams) -> Self {
        Self {
            gpu: gpu.clone(),
            triangles: triangles.to_vec(),
            params,
            last_stats: DacrtStats::default(),
            last_time: Duration::ZERO,
        }
    }

    pub fn params(&self) -> DacrtParams {
        self.params
    }

    /// Statistics of the last [`Tracer::trace`].
    pub fn last_stats(&self) -> DacrtStats {
        self.last_stats
    }

    /// CPU time of the last traversal alone (no readback or upload).
    pub fn last_trace_time(&self) -> Duration {
        self.last_time
    }
}

impl Tracer for CpuDacrtTracer {
    fn name(&self) -> &'static str {
        "cpu-dacrt"
    }

    /// DACRT builds nothing: new geometry is a copy of the triangle list.
    fn set_geometry(&mut self, triangles: &[GpuTriangle]) -> vk::Result<()> {
        self.triangles = triangles.to_vec();
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
        let (triangles, params) = (&self.triangles, &self.params);
        let (point, traced) = trace_on_host(
            &self.gpu,
            "cpu-dacrt",
            (rays, hits),
            ray_count,
            after,
            |host_rays| {
                let _span =
                    tracing::info_span!("cpu-dacrt trace", rays = host_rays.len() as u64).entered();
                trace(host_rays, triangles, query, params)
            },
        )?;
        if let Some((time, stats)) = traced {
            self.last_time = time;
            self.last_stats = stats;
        }
        Ok(point)
    }
}
