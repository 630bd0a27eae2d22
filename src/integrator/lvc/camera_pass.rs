//! The camera pass (thesis Algorithm 8): a chunk's camera subpaths as a wavefront,
//! bounce by bounce —
//!
//! 1. trace (line 4) and sort by material key (line 5, optional);
//! 2. `camera_vertex`: the vertex each path reached and its emitter hit (s = 0);
//! 3. three kernels on three streams (lines 6–8), each after step 2 and independent of
//!    the others: direct lighting (s = 1) on [`StreamKind::Aux0`], connections to the
//!    light vertex cache on [`StreamKind::Aux1`], the next bounce on
//!    [`StreamKind::Main`]; they read the vertex records and write disjoint buffers (the
//!    shadow rays and contributions of direct lighting and of connections are disjoint
//!    ranges of one buffer, the next bounce writes the path states and rays);
//! 4. the shadow rays of direct lighting and connections traced together, after all
//!    three (line 9);
//! 5. `camera_accumulate`: unoccluded contributions join their path's radiance, in a
//!    fixed order, and the bounce's shadow rays are tallied ([`Visibility`]); the live
//!    paths are compacted (line 10).
//!
//! Then `finish` adds each pixel's pass estimates (radiance + light-tracing splats) to
//! the film. With one stream every kernel is recorded on the main stream in the same
//! order; the kernels' outputs do not depend on their order, so the image is the same
//! bit for bit.

use super::gpu::{LvcPush, VisibilityTally};
use super::light_pass::gather;
use super::Shared;
use crate::trace::{Query, Tracer};
use crate::vk::{self, Buffer, StreamKind, TimelinePoint};

/// Which streams the three kernels of a bounce run on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Streams {
    pub direct: StreamKind,
    pub connect: StreamKind,
}

impl Streams {
    /// `count` = 3: direct lighting and connections on the auxiliary streams (which
    /// share the main queue on a device with one queue); 1: all on the main stream.
    pub fn new(count: u32) -> Self {
        if count >= 3 {
            Self {
                direct: StreamKind::Aux0,
                connect: StreamKind::Aux1,
            }
        } else {
            Self {
                direct: StreamKind::Main,
                connect: StreamKind::Main,
            }
        }
    }
}

/// Where a chunk's camera pass puts its results.
pub struct CameraTargets<'a> {
    pub splat_film: &'a Buffer,
    pub accum: &'a Buffer,
    pub accum2: &'a Buffer,
    pub counters: &'a Buffer,
}

/// The camera paths of a chunk: pixels `pixel_offset..pixel_offset + pixel_count` in
/// `passes` passes from `first_pass` (path c: pixel pixel_offset + c mod pixel_count,
/// pass first_pass + c / pixel_count).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CameraRange {
    pub first_pass: u32,
    pub passes: u32,
    pub pixel_offset: u32,
    pub pixel_count: u32,
}

/// What one camera bounce left in the wavefront's buffers, for callers that look
/// (technique images, tests): read them in the hook.
pub struct BounceView {
    pub range: CameraRange,
    pub bounce: u32,
    /// Which of the wavefront's two active lists holds the live paths.
    pub list: usize,
    /// Live paths this bounce.
    pub paths: u32,
    /// First slot of the connections' shadow rays and contributions.
    pub connection_base: u32,
}

/// Called after every camera bounce's accumulation, before compaction.
pub type BounceHook<'h> = dyn FnMut(&Shared, &BounceView) -> vk::Result<()> + 'h;

/// What a camera pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CameraPassOutcome {
    pub rays: u64,
    /// Shadow-ray slots handed to the tracer (empty ones included).
    pub shadow_rays: u64,
    pub bounces: u32,
    pub visibility: Visibility,
}

/// Shadow rays that carried a contribution and those found unoccluded, summed over
/// bounces (each bounce's [`VisibilityTally`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Visibility {
    pub direct_rays: u64,
    pub direct_unoccluded: u64,
    pub connection_rays: u64,
    pub connections_unoccluded: u64,
}

impl From<VisibilityTally> for Visibility {
    fn from(t: VisibilityTally) -> Self {
        Self {
            direct_rays: t.direct_rays.into(),
            direct_unoccluded: t.direct_unoccluded.into(),
            connection_rays: t.connection_rays.into(),
            connections_unoccluded: t.connections_unoccluded.into(),
        }
    }
}

impl Visibility {
    pub fn merge(&mut self, other: &Visibility) {
        self.direct_rays += other.direct_rays;
        self.direct_unoccluded += other.direct_unoccluded;
        self.connection_rays += other.connection_rays;
        self.connections_unoccluded += other.connections_unoccluded;
    }
}

/// The first connection slot after `n` direct-lighting slots: the next multiple of
/// the device's storage-buffer offset alignment (in 32-byte slots).
pub fn connection_base(shared: &Shared, n: u32) -> u32 {
    let align = shared
        .gpu
        .info()
        .limits
        .min_storage_buffer_offset_alignment
        .max(32);
    let per = (align / 32) as u32;
    n.div_ceil(per) * per
}

/// Traces the camera paths of `range` and adds their pass estimates to the film.
pub fn trace_camera_paths(
    shared: &Shared,
    tracer: &mut dyn Tracer,
    streams: Streams,
    targets: &CameraTargets,
    range: CameraRange,
    hook: &mut BounceHook,
) -> vk::Result<CameraPassOutcome> {
    let paths = range.passes * range.pixel_count;
    let _span = tracing::info_span!("lvc camera pass", paths).entered();
    let w = shared.wave;
    let mut push = LvcPush {
        first_pass: range.first_pass,
        path_count: paths,
        pixel_offset: range.pixel_offset,
        pixel_count: range.pixel_count,
        ..Default::default()
    };
    let mut ready = generate_camera_paths(shared, &push, paths)?;
    let mut outcome = CameraPassOutcome::default();
    let (mut cur, mut n) = (0usize, paths);
    while n > 0 {
        crate::timeline_counter!("lvc", "live camera paths", n);
        let _bounce = tracing::info_span!("lvc camera bounce", paths = n).entered();
        outcome.bounces += 1;
        push.active_count = n;
        push.bounce = outcome.bounces;
        push.base = connection_base(shared, n);
        let traced = tracer.trace(&w.rays[cur], &w.hits, n, Query::ClosestHit, &[&ready])?;
        outcome.rays += n as u64;
        let vertexed = record_vertices(shared, cur, n, &push, &traced)?;
        let shadows = push.base + n * shared.connections;
        let done = record_techniques(shared, streams, cur, n, &push, &vertexed)?;
        let occluded = trace_shadow_rays(shared, tracer, shadows, &done)?;
        outcome.shadow_rays += shadows as u64;
        let (survivors, tally) = accumulate_and_compact(shared, targets, cur, n, &push, &occluded)?;
        outcome.visibility.merge(&tally.into());
        hook(
            shared,
            &BounceView {
                range,
                bounce: outcome.bounces,
                list: cur,
                paths: n,
                connection_base: push.base,
            },
        )?;
        if survivors == 0 {
            break;
        }
        ready = gather(shared, cur, survivors)?;
        cur = 1 - cur;
        n = survivors;
    }
    crate::timeline_counter!("lvc", "live camera paths", 0);
    finish_pixels(shared, targets, &push, range.pixel_count)?;
    Ok(outcome)
}

/// The chunk's `paths` camera paths, started in list 0.
fn generate_camera_paths(shared: &Shared, push: &LvcPush, paths: u32) -> vk::Result<TimelinePoint> {
    let w = shared.wave;
    let mut rec = shared.gpu.recorder(StreamKind::Main)?;
    rec.dispatch_items(
        &shared.kernels.camera_generate,
        &[
            shared.constants.into(),
            (&w.rays[0]).into(),
            (&w.active[0]).into(),
            (&w.paths).into(),
            (&w.radiance).into(),
        ],
        push,
        paths as u64,
    )?;
    rec.submit(&[])
}

/// Step 4: the `count` shadow rays of direct lighting and connections, traced together
/// after all three kernels (`done`).
fn trace_shadow_rays(
    shared: &Shared,
    tracer: &mut dyn Tracer,
    count: u32,
    done: &[TimelinePoint],
) -> vk::Result<TimelinePoint> {
    let w = shared.wave;
    let waits: Vec<&TimelinePoint> = done.iter().collect();
    tracer.trace(
        &w.shadow_rays,
        &w.shadow_hits,
        count,
        Query::Occlusion,
        &waits,
    )
}

/// Step 5 after the shadow rays (`occluded`), waited for: `camera_accumulate`, then the
/// compaction of the live paths; (survivors, the bounce's shadow-ray tally).
fn accumulate_and_compact(
    shared: &Shared,
    targets: &CameraTargets,
    cur: usize,
    n: u32,
    push: &LvcPush,
    occluded: &TimelinePoint,
) -> vk::Result<(u32, VisibilityTally)> {
    let w = shared.wave;
    let mut rec = shared.gpu.recorder(StreamKind::Main)?;
    rec.fill(&w.tally, 0);
    rec.barrier();
    rec.dispatch_items(
        &shared.kernels.camera_accumulate,
        &[
            shared.constants.into(),
            (&w.active[cur]).into(),
            (&w.emitted).into(),
            (&w.shadow_hits).into(),
            (&w.contributions).into(),
            (&w.radiance).into(),
            targets.counters.into(),
            (&w.tally).into(),
        ],
        push,
        n as u64,
    )?;
    rec.barrier();
    w.record_compact(&mut rec, n, &w.alive, &w.kept, &w.count_alive)?;
    w.record_counts_readback(&mut rec);
    w.record_tally_readback(&mut rec);
    let counted = rec.submit(&[occluded])?;
    shared.gpu.wait(&counted)?;
    w.read_camera_counts(n, &counted)
}

/// `finish`: each of the chunk's `pixel_count` pixels' pass estimates added to the film,
/// waited for.
fn finish_pixels(
    shared: &Shared,
    targets: &CameraTargets,
    push: &LvcPush,
    pixel_count: u32,
) -> vk::Result<()> {
    let mut rec = shared.gpu.recorder(StreamKind::Main)?;
    rec.dispatch_items(
        &shared.kernels.finish,
        &[
            shared.constants.into(),
            (&shared.wave.radiance).into(),
            targets.splat_film.into(),
            targets.accum.into(),
            targets.accum2.into(),
        ],
        push,
        pixel_count as u64,
    )?;
    shared.gpu.wait(&rec.submit(&[])?)
}

/// Step 2: sort (optional) and `camera_vertex` on the main stream after the trace.
fn record_vertices(
    shared: &Shared,
    cur: usize,
    n: u32,
    push: &LvcPush,
    traced: &TimelinePoint,
) -> vk::Result<TimelinePoint> {
    let (k, s, w) = (shared.kernels, shared.scene, shared.wave);
    let mut rec = shared.gpu.recorder(StreamKind::Main)?;
    shared.record_sort(&mut rec, n)?;
    rec.dispatch_items(
        &k.camera_vertex,
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
            (&s.normals).into(),
            (&s.tri_pmf).into(),
            (&w.vertices).into(),
            (&w.emitted).into(),
        ],
        push,
        n as u64,
    )?;
    rec.submit(&[traced])
}

/// Step 3: direct lighting, connections and the next bounce, each on its stream after
/// `vertexed`; the points that mark them done.
fn record_techniques(
    shared: &Shared,
    streams: Streams,
    cur: usize,
    n: u32,
    push: &LvcPush,
    vertexed: &TimelinePoint,
) -> vk::Result<Vec<TimelinePoint>> {
    let (gpu, k, s, w) = (shared.gpu, shared.kernels, shared.scene, shared.wave);
    let slot = size_of::<crate::trace::Ray>() as u64;
    let contribution = size_of::<super::gpu::Contribution>() as u64;
    let base = push.base as u64;
    let connections = (n * shared.connections) as u64;
    let mut done = Vec::new();

    let mut rec = gpu.recorder(streams.direct)?;
    rec.dispatch_items(
        &k.camera_direct,
        &[
            shared.constants.into(),
            (&w.active[cur]).into(),
            (&w.order).into(),
            (&w.vertices).into(),
            (&s.triangles).into(),
            (&s.bsdfs).into(),
            (&s.lights).into(),
            (&s.light_cdf).into(),
            w.shadow_rays.slice(0, base * slot),
            w.contributions.slice(0, base * contribution),
        ],
        push,
        base,
    )?;
    done.push(rec.submit(&[vertexed])?);

    let mut rec = gpu.recorder(streams.connect)?;
    rec.dispatch_items(
        &k.camera_connect,
        &[
            shared.constants.into(),
            (&w.active[cur]).into(),
            (&w.order).into(),
            (&w.vertices).into(),
            (&s.triangles).into(),
            (&s.bsdfs).into(),
            (&shared.cache.vertices).into(),
            (&shared.cache.index).into(),
            (&shared.cache.path_offset).into(),
            w.shadow_rays.slice(base * slot, connections * slot),
            w.contributions
                .slice(base * contribution, connections * contribution),
        ],
        push,
        n as u64,
    )?;
    done.push(rec.submit(&[vertexed])?);

    let mut rec = gpu.recorder(StreamKind::Main)?;
    rec.dispatch_items(
        &k.camera_bounce,
        &[
            shared.constants.into(),
            (&w.rays[cur]).into(),
            (&w.active[cur]).into(),
            (&w.order).into(),
            (&w.vertices).into(),
            (&w.paths).into(),
            (&s.triangles).into(),
            (&s.bsdfs).into(),
            (&w.alive).into(),
        ],
        push,
        n as u64,
    )?;
    done.push(rec.submit(&[vertexed])?);
    Ok(done)
}
