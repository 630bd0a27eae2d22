//! Light tracing (t = 1): every cache vertex connected to the pinhole, in batches of the
//! wavefront's shadow-ray buffer — `light_connect` (the pixel, the weighted contribution
//! and the shadow ray), the shadow rays traced, and `splat` (unoccluded contributions
//! added to the chunk's splat film in fixed point, so that the sums are the same in any
//! order: [`super::fixed`]).

use super::gpu::LvcPush;
use super::Shared;
use crate::trace::{Query, Tracer};
use crate::vk::{self, Buffer, StreamKind};

/// One batch's place in the cache, for callers that look at its contributions.
pub struct SplatBatch {
    /// First cache vertex.
    pub base: u32,
    pub count: u32,
}

/// Connects cache vertices `0..vertices` to the camera and splats them into
/// `splat_film`; `hook` sees each batch's contributions and shadow hits. Returns the
/// rays traced.
pub fn splat_cache(
    shared: &Shared,
    tracer: &mut dyn Tracer,
    vertices: u32,
    splat_film: &Buffer,
    counters: &Buffer,
    hook: &mut dyn FnMut(&Shared, &SplatBatch) -> vk::Result<()>,
) -> vk::Result<u64> {
    let _span = tracing::info_span!("lvc light tracing", vertices).entered();
    let (gpu, k, s, w) = (shared.gpu, shared.kernels, shared.scene, shared.wave);
    let batch = w.shadow_capacity;
    let mut rays = 0u64;
    let mut base = 0u32;
    while base < vertices {
        let count = batch.min(vertices - base);
        let push = LvcPush {
            active_count: count,
            base,
            ..Default::default()
        };
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &k.light_connect,
            &[
                shared.constants.into(),
                (&shared.cache.vertices).into(),
                (&s.triangles).into(),
                (&s.bsdfs).into(),
                (&w.shadow_rays).into(),
                (&w.contributions).into(),
            ],
            &push,
            count as u64,
        )?;
        let connected = rec.submit(&[])?;
        let occluded = tracer.trace(
            &w.shadow_rays,
            &w.shadow_hits,
            count,
            Query::Occlusion,
            &[&connected],
        )?;
        rays += count as u64;
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &k.splat,
            &[
                (&w.contributions).into(),
                (&w.shadow_hits).into(),
                splat_film.into(),
                counters.into(),
                shared.constants.into(),
            ],
            &push,
            count as u64,
        )?;
        gpu.wait(&rec.submit(&[&occluded])?)?;
        hook(shared, &SplatBatch { base, count })?;
        base += count;
    }
    Ok(rays)
}
