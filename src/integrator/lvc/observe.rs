//! What a chunk leaves in the GPU's buffers at each stage, shown to callers that look:
//! the technique images (`techniques`) and the tests that compare the kernels with their
//! CPU twins. The buffers are the wavefront's and the cache's ([`Shared`]); an observer
//! reads what it needs (each read waits for the GPU).

use super::camera_pass::BounceView;
use super::light_tracing::SplatBatch;
use super::Shared;
use crate::vk::{self, Buffer};

/// A chunk of passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChunkView {
    pub first_pass: u32,
    pub passes: u32,
    /// Light paths of the chunk (all its passes').
    pub light_paths: u32,
    /// Vertices in the light vertex cache.
    pub vertices: u32,
}

pub trait Observer {
    /// After the light pass: the cache, its index and the per-path counts and offsets.
    fn light_pass(&mut self, _shared: &Shared, _chunk: &ChunkView) -> vk::Result<()> {
        Ok(())
    }
    /// After each light-tracing batch: its contributions, shadow rays and hits.
    fn splats(
        &mut self,
        _shared: &Shared,
        _chunk: &ChunkView,
        _batch: &SplatBatch,
    ) -> vk::Result<()> {
        Ok(())
    }
    /// After light tracing: the chunk's splat film (fixed point, per pass and pixel).
    fn splat_film(&mut self, _film: &Buffer, _chunk: &ChunkView) -> vk::Result<()> {
        Ok(())
    }
    /// After each camera bounce's accumulation, before compaction.
    fn bounce(
        &mut self,
        _shared: &Shared,
        _chunk: &ChunkView,
        _view: &BounceView,
    ) -> vk::Result<()> {
        Ok(())
    }
    /// After the chunk's pass estimates joined the film.
    fn end_chunk(&mut self, _chunk: &ChunkView) {}
}

/// Looks at nothing.
pub struct NoObserver;

impl Observer for NoObserver {}
