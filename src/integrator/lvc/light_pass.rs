//! The light pass (thesis Algorithm 7): a chunk's light subpaths as a wavefront through
//! the [`Tracer`], bounce by bounce — trace (line 4), sort by material key (line 5,
//! optional), evaluate the material at the hit and sample the next direction (lines 6
//! and 8, `light_shade.comp`), store the connectible vertices in the light vertex cache
//! (line 7, compaction of the marks + `light_store.comp`), compact the live paths
//! (line 9) — until every path has ended. Then the cache's per-path index.

use super::cache::LightCache;
use super::gpu::LvcPush;
use super::kernels::pt_params;
use super::Shared;
use crate::trace::{Query, Tracer};
use crate::vk::{self, StreamKind, TimelinePoint};

/// What a light pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LightPassOutcome {
    /// Vertices the chunk's light subpaths made for the cache (all of them stored when
    /// this is at most the capacity).
    pub vertices: u64,
    /// Rays traced.
    pub rays: u64,
    /// Bounces.
    pub bounces: u32,
}

impl LightPassOutcome {
    pub fn fits(&self, cache: &LightCache) -> bool {
        self.vertices <= cache.capacity as u64
    }
}

/// Traces light paths `0..paths` of the chunk whose first pass is `first_pass` (path l
/// is light path l mod N_L of pass first_pass + l / N_L) into `cache`, and records its
/// index when they fit. The caller grows the cache and calls again when they do not.
pub fn trace_light_paths(
    shared: &Shared,
    tracer: &mut dyn Tracer,
    cache: &LightCache,
    first_pass: u32,
    paths: u32,
) -> vk::Result<LightPassOutcome> {
    let _span = tracing::info_span!("lvc light pass", paths).entered();
    let w = shared.wave;
    let mut push = LvcPush {
        first_pass,
        path_count: paths,
        capacity: cache.capacity,
        ..Default::default()
    };
    let mut ready = generate_light_paths(shared, cache, &push, paths)?;
    let mut outcome = LightPassOutcome::default();
    let (mut cur, mut n) = (0usize, paths);
    while n > 0 {
        crate::timeline_counter!("lvc", "live light paths", n);
        let _bounce = tracing::info_span!("lvc light bounce", paths = n).entered();
        outcome.bounces += 1;
        push.active_count = n;
        push.bounce = outcome.bounces;
        push.base = outcome.vertices.min(u32::MAX as u64) as u32;
        let traced = tracer.trace(&w.rays[cur], &w.hits, n, Query::ClosestHit, &[&ready])?;
        outcome.rays += n as u64;
        let (marked, survivors) = shade_and_store(shared, cache, cur, n, &push, &traced)?;
        outcome.vertices += marked as u64;
        if survivors == 0 {
            break;
        }
        ready = gather(shared, cur, survivors)?;
        cur = 1 - cur;
        n = survivors;
    }
    crate::timeline_counter!("lvc", "live light paths", 0);
    if outcome.fits(cache) {
        index_cache(shared, cache, paths, outcome.vertices as u32)?;
    }
    Ok(outcome)
}

/// Clears the paths' vertex counts and starts `paths` light paths in list 0.
fn generate_light_paths(
    shared: &Shared,
    cache: &LightCache,
    push: &LvcPush,
    paths: u32,
) -> vk::Result<TimelinePoint> {
    let (s, w) = (shared.scene, shared.wave);
    let mut rec = shared.gpu.recorder(StreamKind::Main)?;
    rec.fill_range(&cache.vertex_count, paths as u64 * 4, 4, 0)?;
    rec.barrier();
    rec.dispatch_items(
        &shared.kernels.light_generate,
        &[
            shared.constants.into(),
            (&s.lights).into(),
            (&s.light_cdf).into(),
            (&w.rays[0]).into(),
            (&w.active[0]).into(),
            (&w.paths).into(),
            (&cache.vertex_count).into(),
        ],
        push,
        paths as u64,
    )?;
    rec.submit(&[])
}

/// Lines 5–9 after the trace: sort (optional), shade, store the marked vertices in the
/// cache and compact the live paths; (vertices marked, survivors).
fn shade_and_store(
    shared: &Shared,
    cache: &LightCache,
    cur: usize,
    n: u32,
    push: &LvcPush,
    traced: &TimelinePoint,
) -> vk::Result<(u32, u32)> {
    let (k, s, w) = (shared.kernels, shared.scene, shared.wave);
    let mut rec = shared.gpu.recorder(StreamKind::Main)?;
    shared.record_sort(&mut rec, n)?;
    rec.dispatch_items(
        &k.light_shade,
        &[
            shared.constants.into(),
            (&w.rays[cur]).into(),
            (&w.hits).into(),
            (&w.active[cur]).into(),
            (&w.order).into(),
            (&w.paths).into(),
            (&s.triangles).into(),
            (&s.triangle_material).into(),
            (&s.materials).into(),
            (&s.bsdfs).into(),
            (&s.normals).into(),
            (&w.vertices).into(),
            (&w.stored).into(),
            (&w.alive).into(),
            (&cache.vertex_count).into(),
        ],
        push,
        n as u64,
    )?;
    rec.barrier();
    w.record_compact(&mut rec, n, &w.stored, &w.kept_vertices, &w.count_marked)?;
    rec.dispatch_items(
        &k.light_store,
        &[
            (&w.kept_vertices).into(),
            (&w.count_marked).into(),
            (&w.vertices).into(),
            (&cache.vertices).into(),
        ],
        push,
        n as u64,
    )?;
    w.record_compact(&mut rec, n, &w.alive, &w.kept, &w.count_alive)?;
    w.record_counts_readback(&mut rec);
    let counted = rec.submit(&[traced])?;
    w.read_counts(n, &counted)
}

/// The cache's per-path index over its `vertices` vertices, waited for.
fn index_cache(shared: &Shared, cache: &LightCache, paths: u32, vertices: u32) -> vk::Result<()> {
    let mut rec = shared.gpu.recorder(StreamKind::Main)?;
    rec.barrier();
    cache.record_index(&mut rec, shared.kernels, paths, vertices)?;
    shared.gpu.wait(&rec.submit(&[])?)
}

/// Moves the `survivors` rays and ids of list `cur` (their indices in `kept`) to the
/// front of the other list, in order.
pub fn gather(shared: &Shared, cur: usize, survivors: u32) -> vk::Result<TimelinePoint> {
    let w = shared.wave;
    let mut rec = shared.gpu.recorder(StreamKind::Main)?;
    rec.dispatch_items(
        &shared.kernels.gather,
        &[
            (&w.kept).into(),
            (&w.rays[cur]).into(),
            (&w.active[cur]).into(),
            (&w.rays[1 - cur]).into(),
            (&w.active[1 - cur]).into(),
        ],
        &pt_params(survivors),
        survivors as u64,
    )?;
    rec.submit(&[])
}
