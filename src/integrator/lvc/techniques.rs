//! Technique images (`--bdpt-techniques DIR`): every contribution that reaches the film,
//! read back after each camera bounce and each light-tracing batch and summed per
//! technique (s, t) on the host, with `bpt`'s images and names
//! ([`crate::integrator::bpt::technique_images`]), so that they sum to the image. Only
//! renders that ask for them pay the readbacks.

use super::camera_pass::BounceView;
use super::gpu::{Contribution, CONTRIBUTION_NONE};
use super::light_tracing::SplatBatch;
use super::observe::{ChunkView, Observer};
use super::Shared;
use crate::integrator::bpt::pass::{ChunkOutput, TechniqueEntry};
use crate::integrator::bpt::technique_images::TechniqueImages;
use crate::integrator::NamedImage;
use crate::trace::{Hit, MISS};
use crate::vk;

pub struct TechniqueRecorder {
    width: u32,
    height: u32,
    images: TechniqueImages,
    /// The current chunk's entries, per pass of the chunk.
    chunk: Vec<Vec<TechniqueEntry>>,
}

fn entry(pixel: u32, c: &Contribution) -> Option<TechniqueEntry> {
    let (s, t) = c.technique();
    let value = c.value();
    (c.code != CONTRIBUTION_NONE && value.is_finite()).then_some(TechniqueEntry {
        pixel,
        s: s as u16,
        t: t as u16,
        rgb: c.value,
        // Already divided by the pass's light paths.
        splat: false,
    })
}

impl TechniqueRecorder {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            images: TechniqueImages::new(width, height),
            chunk: Vec::new(),
        }
    }

    fn pass(&mut self, pass_in_chunk: usize) -> &mut Vec<TechniqueEntry> {
        if self.chunk.len() <= pass_in_chunk {
            self.chunk.resize_with(pass_in_chunk + 1, Vec::new);
        }
        &mut self.chunk[pass_in_chunk]
    }

    /// Starts the images anew (a restored film).
    pub fn clear(&mut self) {
        self.images = TechniqueImages::new(self.width, self.height);
        self.chunk.clear();
    }

    pub fn images(&self) -> Vec<NamedImage> {
        self.images.images()
    }
}

impl Observer for TechniqueRecorder {
    /// The unoccluded splats of a light-tracing batch.
    fn splats(
        &mut self,
        shared: &Shared,
        _chunk: &ChunkView,
        batch: &SplatBatch,
    ) -> vk::Result<()> {
        let pixels = self.width * self.height;
        let contributions: Vec<Contribution> = shared.wave.contributions.read()?;
        let hits: Vec<Hit> = shared.wave.shadow_hits.read()?;
        for k in 0..batch.count as usize {
            let c = &contributions[k];
            if hits[k].triangle != MISS || !c.is_some() {
                continue;
            }
            if let Some(e) = entry(c.target % pixels, c) {
                self.pass((c.target / pixels) as usize).push(e);
            }
        }
        Ok(())
    }

    /// A camera bounce's emitter hits and unoccluded direct lighting and connections.
    fn bounce(&mut self, shared: &Shared, _chunk: &ChunkView, view: &BounceView) -> vk::Result<()> {
        let (pixel_offset, pixel_count) = (view.range.pixel_offset, view.range.pixel_count);
        let w = shared.wave;
        let active: Vec<u32> = w.active[view.list].read()?;
        let emitted: Vec<Contribution> = w.emitted.read()?;
        let contributions: Vec<Contribution> = w.contributions.read()?;
        let hits: Vec<Hit> = w.shadow_hits.read()?;
        let n = shared.connections as usize;
        for i in 0..view.paths as usize {
            let path = active[i];
            let pixel = pixel_offset + path % pixel_count;
            let pass = (path / pixel_count) as usize;
            let mut slots = vec![
                (&emitted[i], true),
                (&contributions[i], hits[i].triangle == MISS),
            ];
            for k in 0..n {
                let slot = view.connection_base as usize + i * n + k;
                slots.push((&contributions[slot], hits[slot].triangle == MISS));
            }
            for (c, visible) in slots {
                if let Some(e) = visible.then(|| entry(pixel, c)).flatten() {
                    self.pass(pass).push(e);
                }
            }
        }
        Ok(())
    }

    /// Adds the chunk's passes to the images.
    fn end_chunk(&mut self, chunk: &ChunkView) {
        for q in 0..chunk.passes as usize {
            let entries = self
                .chunk
                .get_mut(q)
                .map(std::mem::take)
                .unwrap_or_default();
            let chunk = ChunkOutput {
                entries,
                ..Default::default()
            };
            self.images.add_pass(std::slice::from_ref(&chunk), 1.0);
        }
        self.chunk.clear();
    }
}
